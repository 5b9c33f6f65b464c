"""The shell of a node that only listens (the recorder, the live fatigue node): it takes each
message as it arrives, before the run's ``start`` as after it. :meth:`Listener.feed` subscribes
to an input; :meth:`Listener.poll` takes one message, verified, decoded and checked (else
rejected and counted; ``hello`` is not returned), handles clock messages (abort:
:class:`RunError`; a plausible ``start`` sets :attr:`Listener.start`) and, until the start,
keeps the handshake going (:class:`cosim.participant.StartBarrier`)."""

from __future__ import annotations

import queue
import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from . import keys
from .control import check_start
from .errors import WireError
from .participant import Channel, Participant, StartBarrier
from .wire import Message


@dataclass(frozen=True)
class Received:
    """One verified, decoded message of a feed: from ``node``, on ``channel`` (key ``key``)."""

    node: str
    channel: str
    key: str
    msg: Message


@dataclass(frozen=True)
class _Feed:
    key: str
    kinds: tuple[str, ...]
    required: tuple[str, ...]


class Listener:
    """The handshake and the input side of a listening node (see the module's docstring)."""

    def __init__(self, part: Participant, start_timeout_s: float,
                 info: Mapping[str, Any] | None = None) -> None:
        self.part = part
        self.start: dict[str, Any] | None = None  # the start payload, once it came
        self.heard: set[Channel] = set()  # feeds a valid message (hello or data) came on
        self.feeds: dict[Channel, _Feed] = {}
        self._barrier = StartBarrier(part, start_timeout_s, info or {})

    def feed(self, node: str, channel: str, kinds: Iterable[str] = ("data",),
             required: Iterable[str] = ()) -> Channel:
        """Subscribe to ``node/channel``: messages of ``kinds`` with the ``required`` fields."""
        tag = (node, channel)
        if tag in self.feeds:
            return tag
        key = keys.key(self.part.run, node, channel)
        self.feeds[tag] = _Feed(key, tuple(kinds), tuple(required))
        put = self.part.inbox.put
        self.part.bus.subscribe(key, lambda _k, raw: put((tag, raw)))
        return tag

    def missing(self) -> list[str]:
        """The feeds not heard yet, as ``node/channel``."""
        return [f"{n}/{c}" for (n, c) in self.feeds if (n, c) not in self.heard]

    def poll(self, timeout: float = 0.05) -> Received | None:
        """One message of a feed, or None (none within ``timeout`` [s], a control message, a
        rejected one); RunError on an abort, the orchestrator gone, or no start in time."""
        part = self.part
        part.check_orchestrator()
        if self.start is None:
            self._barrier.tick(self.missing())
        try:
            tag, raw = part.inbox.get(timeout=timeout)
        except queue.Empty:
            return None
        feed = self.feeds.get(tag)
        if feed is not None:
            return self._open(tag, feed, raw)
        msg = part.handle(tag, raw)  # the clock: raises RunError on an abort
        if msg is not None and msg.kind == "start" and self.start is None:
            try:
                check_start(msg.d, **part.expect_start)
            except WireError as exc:  # a forged or foreign start: not acted on
                part.reject(tag, str(exc))
                return None
            self.start = dict(msg.d)
            part.ctl("progress", -1, 0.0, rejected=part.rejected)
        return None

    def _open(self, tag: Channel, feed: _Feed, raw: bytes) -> Received | None:
        try:
            msg = self.part.open(feed.key, raw)  # signed with the run's key, else rejected
        except WireError as exc:
            self.part.reject(tag, str(exc))
            return None
        if msg.kind == "hello":
            self.heard.add(tag)
            return None
        if msg.kind not in feed.kinds:
            self.part.reject(tag, f"unexpected kind '{msg.kind}' on {tag[0]}/{tag[1]}")
            return None
        missing = [f for f in feed.required if f not in msg.d]
        if missing:
            self.part.reject(tag, f"step {msg.k}: missing field(s) {', '.join(missing)}")
            return None
        self.heard.add(tag)
        return Received(tag[0], tag[1], feed.key, msg)

    def drain(self, quiet_s: float = 0.3, limit_s: float = 1.5) -> list[Received]:
        """After an abort: the feeds' messages that still come until the bus is quiet."""
        out: list[Received] = []
        end = time.monotonic() + limit_s
        while time.monotonic() < end:
            try:
                tag, raw = self.part.inbox.get(timeout=quiet_s)
            except queue.Empty:
                break
            feed = self.feeds.get(tag)
            if feed is not None and (got := self._open(tag, feed, raw)) is not None:
                out.append(got)
        return out
