"""The lock-step participant: what every node does around its model (DESIGN.md, "Lock-step
co-simulation"): a liveliness token, the resolved scenario fetched, the start handshake
(:class:`StartBarrier`), then per step :meth:`Participant.wait` for its inputs (one FIFO per
producer, read by the node's own thread; a watchdog thread wakes it on stall timeout, an
abort, or the orchestrator gone) and one signed ``<node>/step`` message of its outputs
(:mod:`cosim.outbox`); ``done`` at the end. A message that does not verify, decode, fit the
schema or its bounded mailbox is rejected: logged, counted, never a crash.
"""

from __future__ import annotations

import contextlib
import logging
import os
import queue
import threading
import time
from collections.abc import Iterable, Iterator, Mapping
from typing import Any

from . import keys
from .auth import RunKey, served_scenario
from .bus import Bus, Feed
from .control import check_clock, check_start
from .errors import InputLate, RunError, WireError
from .mailbox import MAILBOX_MAX, MAILBOX_WINDOW, Mailbox, file_step
from .orchestrator_presence import OrchestratorPresence, parent_from_env
from .outbox import Outbox
from .wire import ChannelCodec, Message, codec, decode, encode

__all__ = ["MAILBOX_MAX", "MAILBOX_WINDOW", "Channel", "Participant"]

log = logging.getLogger("suscosim.node")

Channel = tuple[str, str]  # (node, channel) of an input

_CLOCK_TAG: Channel = (keys.ORCHESTRATOR, keys.CLOCK)
HELLO_PERIOD_S = 0.05
PROGRESS_PERIOD_S = 0.1
WAITING_PERIOD_S = 1.0
WATCHDOG_PERIOD_S = 0.05
"""How often the watchdog looks at a node blocked on an input (bounds the abort latency)."""
FEED_CAPACITY = 1024
"""Messages an input's FIFO holds; lock-step producers are at most a few steps ahead."""


class Participant:
    """One node's side of the lock-step protocol, on any bus."""

    def __init__(self, bus: Bus, run: str, node: str, stall_timeout_s: float = 10.0,
                 spin_s: float = 0.0, auth: RunKey | None = None) -> None:
        self.bus, self.run, self.node = bus, keys.check_name("run", run), node
        self.auth = auth  # None: no signing nor verifying (tests of the protocol alone)
        self.expect_start: dict[str, Any] = {}  # kwargs of control.check_start
        self.stall_timeout_s = stall_timeout_s
        self.spin_s = spin_s  # [s] wait polls an input this long before it blocks
        self.inbox: queue.SimpleQueue[tuple[Channel, bytes]] = queue.SimpleQueue()
        self.feeds: dict[Channel, Any] = {}  # stepped input -> its producer's FIFO
        self._pfeeds: dict[str, Any] = {}  # producer node -> the FIFO of its steps
        self._ptag: dict[Channel, Channel] = {}  # stepped input -> (producer, "step")
        self.inputs: dict[Channel, Mailbox] = {}
        self._keyof: dict[Channel, str] = {_CLOCK_TAG: keys.key(run, *_CLOCK_TAG)}
        self.rejected = 0
        self._codecs: dict[str, ChannelCodec | bool] = {}
        self.out = Outbox(self._publisher, run, node)
        self._ctl = self._publisher(keys.key(run, node, keys.CTL))
        self._last_progress = 0.0
        self._token = bus.token(keys.key(run, node, keys.ALIVE))
        self._listen(_CLOCK_TAG)
        self.orchestrator = OrchestratorPresence(self.run, node, parent_from_env())
        bus.watch(keys.key(run, keys.ORCHESTRATOR, keys.ALIVE), self.orchestrator.on_token)
        self._blocked: tuple[Any, float] | None = None  # (feed, stall deadline) while waiting
        self._awaited: tuple[Channel, int, float] | None = None  # (input, k, since [s])
        self._last_waiting = 0.0
        self._wakes = 0  # wake-ups sent by the watchdog, not yet received
        self._wake_lock = threading.Lock()
        self._closed = threading.Event()
        self._watchdog: threading.Thread | None = None

    def check_orchestrator(self) -> None:
        """RunError if the orchestrator is gone (:mod:`cosim.orchestrator_presence`)."""
        why = self.orchestrator.why_gone()
        if why is not None:
            raise RunError(why)

    # ---- wiring -------------------------------------------------------------------------
    def _publisher(self, key: str) -> Any:
        pub = self.bus.publisher(key)
        if self.auth is None:
            return pub
        sign = self.auth.signer(key)
        return lambda raw: pub(sign(raw))

    def open(self, key: str, raw: bytes) -> Message:
        """Verify and decode a message received on ``key`` (a data channel's against its
        schema); :class:`WireError` (:class:`cosim.auth.AuthError`: signature)."""
        body = self.auth.verify(key, raw) if self.auth is not None else raw
        dec = self._codecs.get(key)
        if dec is None:
            dec = self._codec_of(key)
        if not isinstance(dec, ChannelCodec):
            return decode(body)
        return dec.decode(body)

    def _codec_of(self, key: str) -> ChannelCodec | bool:
        """The codec of ``key``'s channel (False: a control key, decoded generically)."""
        try:
            _, node, channel = keys.parse_key(key)
        except ValueError:
            return False
        dec: ChannelCodec | bool = False
        if node != keys.ORCHESTRATOR and channel not in (keys.CTL, keys.ALIVE):
            dec = codec(f"{node}/{channel}")
        if len(self._codecs) < 256:
            self._codecs[key] = dec
        return dec

    def _listen(self, tag: Channel) -> None:
        put = self.inbox.put
        self.bus.subscribe(keys.key(self.run, *tag), lambda _k, raw: put((tag, raw)))

    def listen(self, node: str, channel: str, required: Iterable[str] = (),
               stepped: bool = True) -> Channel:
        """Subscribe to an input (a message without the ``required`` fields is rejected); a
        ``stepped`` one is read by :meth:`wait`, others come through :attr:`inbox`."""
        tag = (node, channel)
        if tag not in self.inputs:
            self.inputs[tag] = Mailbox(tuple(required), stepped)
            if stepped:  # in the producer's step message: one FIFO per producer
                ptag = self._ptag[tag] = (node, keys.STEP)
                if node not in self._pfeeds:
                    self._keyof[ptag] = keys.key(self.run, *ptag)
                    self._pfeeds[node] = self.bus.feed(self._keyof[ptag], FEED_CAPACITY)
                self.feeds[tag] = self._pfeeds[node]
            else:
                self._keyof[tag] = keys.key(self.run, *tag)
                self._listen(tag)
        return tag

    def start_at(self, k: int) -> None:
        """Start at step ``k`` (a resume): stepped inputs' windows at k - 1 (a lagged state)."""
        for mb in (mb for mb in self.inputs.values() if mb.stepped):
            mb.floor = max(k - 1, 0)

    # Sending: :class:`cosim.outbox.Outbox`'s verbs.
    @property
    def outputs(self) -> list[str]:
        return self.out.outputs

    def output(self, channel: str) -> None:
        self.out.output(channel)

    def bind(self, nonce: bytes) -> None:
        """Sign and verify bound to the run instance's ``nonce`` from now on."""
        if self.auth is None or self.auth.nonce == nonce:
            return
        self.auth = self.auth.bound(nonce)
        self._ctl = self._publisher(keys.key(self.run, self.node, keys.CTL))
        self.out.rebind(self._publisher)

    def fetch_scenario(self, timeout_s: float = 30.0) -> dict[str, Any]:
        """The resolved scenario, signed with the run's key (retried); binds to its nonce."""
        deadline = time.monotonic() + timeout_s
        key = keys.key(self.run, keys.ORCHESTRATOR, keys.SCENARIO)
        tag = (keys.ORCHESTRATOR, keys.SCENARIO)
        while time.monotonic() < deadline:
            for raw in self.bus.query_all(key, timeout=1.0):
                try:
                    scenario, nonce = served_scenario(key, raw, self.auth)
                except WireError as exc:
                    self.reject(tag, str(exc))
                    continue
                if nonce is not None:
                    self.bind(nonce)
                return scenario
            self.check_orchestrator()
            time.sleep(0.1)
        raise RunError(f"{self.node}: no orchestrator answered for run '{self.run}' "
                       f"within {timeout_s:.0f} s (is it running, and is --connect right?)")

    # ---- messages -----------------------------------------------------------------------
    def publish(self, channel: str, k: int, t: float, data: Mapping[str, Any],
                record: bool = True, hold: bool = False) -> None:
        self.out.publish(channel, k, t, data, record, hold)

    def send(self) -> None:
        self.out.send()

    def flush_records(self) -> None:
        self.out.flush()

    def publish_hello(self) -> None:
        self.out.hello()

    def ctl(self, kind: str, k: int = -1, t: float = 0.0, **d: Any) -> None:
        """A control message to the orchestrator (ready, progress, done, error)."""
        self._ctl(encode(kind, k, t, d))

    def progress(self, k: int, t: float) -> None:
        now = time.monotonic()
        if now - self._last_progress >= PROGRESS_PERIOD_S:
            self._last_progress = now
            self.check_orchestrator()
            self.ctl("progress", k, t, rejected=self.rejected)

    def poll_control(self) -> None:
        """Handle the control messages that came (RunError on an abort) and check the
        orchestrator: for a node waiting on something other than an input."""
        self._drain_inbox()
        self.check_orchestrator()

    def reject(self, tag: Channel, why: str) -> None:
        """Count and log (the first ten, then every thousandth) a rejected message."""
        self.rejected += 1
        if self.rejected <= 10 or self.rejected % 1000 == 0:
            log.warning("%s: rejected message #%d on %s/%s: %s",
                        self.node, self.rejected, tag[0], tag[1], why)

    def _take(self, timeout: float) -> Message | None:
        return self.handle(*self.inbox.get(timeout=timeout))

    def _poll(self, feed: Feed) -> bytes | None:
        """The next message of ``feed`` if it comes within :attr:`spin_s`, else None."""
        end = time.perf_counter() + self.spin_s
        while (raw := feed.try_recv()) is None and time.perf_counter() < end:
            os.sched_yield()  # the other node on this core runs if it can
        return raw

    def _drain_feeds(self) -> None:
        for node, feed in self._pfeeds.items():
            while (raw := feed.try_recv()) is not None:
                self._receive((node, keys.STEP), raw)

    def _drain_inbox(self) -> None:
        while True:
            try:
                self._take(timeout=0)
            except queue.Empty:
                return

    def _receive(self, tag: Channel, raw: bytes) -> None:
        """One message from an input's FIFO: an empty one is the watchdog's wake-up."""
        if raw:
            self.handle(tag, raw)
            return
        with self._wake_lock:
            woken, self._wakes = self._wakes > 0, max(0, self._wakes - 1)
        if not woken:
            self.reject(tag, "empty message")

    def _watch(self) -> None:
        """Wake the blocked node on a control message, a stall timeout or the orchestrator gone."""
        while not self._closed.wait(WATCHDOG_PERIOD_S):
            blocked = self._blocked
            if blocked is None:
                continue
            feed, deadline = blocked
            now = time.monotonic()
            self._say_waiting(now)
            if not self.inbox.empty() or now >= deadline or \
                    self.orchestrator.why_gone() is not None:
                with self._wake_lock:
                    self._wakes += 1
                feed.wake()

    def _say_waiting(self, now: float) -> None:
        """``waiting`` (the input and step this node is blocked on, so that a stall is blamed
        on the node that stopped) every :data:`WAITING_PERIOD_S` while it is blocked."""
        awaited = self._awaited
        if awaited is None or now - awaited[2] < WAITING_PERIOD_S \
                or now - self._last_waiting < WAITING_PERIOD_S:
            return
        self._last_waiting = now
        (node, channel), k, _ = awaited
        try:
            self.ctl("waiting", k, 0.0, missing=[f"{node}/{channel}"])
        except Exception:  # the session is closing: the main thread will say why
            pass

    def _file_step(self, ptag: Channel, raw: bytes) -> None:
        """File a producer's step message (``ptag``: ``(producer, "step")``) in the mailboxes."""
        try:
            msg = self.open(self._keyof[ptag], raw)
        except WireError as exc:
            self.reject(ptag, str(exc))
            return
        for where, reason in file_step(self.inputs, ptag[0], msg):
            self.reject(where, reason)

    def handle(self, tag: Channel, raw: bytes) -> Message | None:
        """Decode and file one received message; return it if it is a clock message."""
        if tag[1] == keys.STEP and tag[0] in self._pfeeds:
            self._file_step(tag, raw)
            return None
        if tag != _CLOCK_TAG and tag not in self.inputs:
            return None  # not an input of this node (e.g. the recorder's raw feed)
        try:
            msg = self.open(self._keyof[tag], raw)
            if tag == _CLOCK_TAG:
                check_clock(msg.kind, msg.d)
        except WireError as exc:
            self.reject(tag, str(exc))
            return None
        if tag == _CLOCK_TAG:
            if msg.kind == "abort":
                raise RunError(f"run aborted by the orchestrator: {msg.d.get('reason', '?')}")
            return msg
        why = self.inputs[tag].file(msg)
        if why is not None:
            self.reject(tag, why)
        return None

    def wait(self, needs: Mapping[Channel, int]) -> dict[Channel, Message]:
        """Block until every ``(input) -> step`` in ``needs`` has arrived (older ones are
        dropped); RunError on abort, :class:`InputLate` after the stall timeout."""
        self.send()  # this node's last step goes out before it waits for the next
        if self._watchdog is None:
            self._watchdog = threading.Thread(target=self._watch, daemon=True,
                                              name=f"{self.node}-watchdog")
            self._watchdog.start()
        deadline = 0.0  # the stall deadline, from the first input that is not there yet
        for tag, k in needs.items():
            box = self.inputs[tag].box
            if k in box:
                continue
            feed, ptag = self.feeds[tag], self._ptag[tag]
            now = time.monotonic()
            deadline = deadline or now + self.stall_timeout_s
            self._awaited = (tag, k, now)
            while k not in box:
                raw = self._poll(feed) if self.spin_s else None
                if raw is None:
                    self._blocked = (feed, deadline)
                    raw = feed.recv()
                    self._blocked = None
                if raw:  # a producer's step (the hot path: no other checks)
                    self._file_step(ptag, raw)
                    continue
                self._receive(ptag, raw)  # empty: the watchdog's wake-up
                self._drain_inbox()  # raises on abort
                self.check_orchestrator()
                if time.monotonic() >= deadline:
                    late = sorted({t[0] for t, j in needs.items()
                                   if j not in self.inputs[t].box})
                    raise InputLate(f"{self.node}: no input from {', '.join(late)} for "
                                    f"{self.stall_timeout_s:.1f} s (step {max(needs.values())})",
                                    late)
        self._awaited = None
        return {tag: self.inputs[tag].take(k) for tag, k in needs.items()}

    def handshake(self, info: Mapping[str, Any] | None = None,
                  timeout_s: float = 60.0) -> dict[str, Any]:
        """The start barrier: the ``start`` payload (``n_steps``, ``h``, ``info``)."""
        barrier = StartBarrier(self, timeout_s, info or {})
        while True:
            due = barrier.tick([f"{n}/{c}" for (n, c), mb in self.inputs.items()
                                if not mb.heard])
            self._drain_feeds()
            try:
                msg = self._take(timeout=min(0.01, due))
            except queue.Empty:
                continue
            if msg is not None and msg.kind == "start":
                try:
                    check_start(msg.d, **self.expect_start)
                except WireError as exc:  # a forged or foreign start: not acted on
                    self.reject(_CLOCK_TAG, str(exc))
                    continue
                self.ctl("progress", -1, 0.0, rejected=self.rejected)
                return msg.d

    def finish(self, k: int, t: float, linger_s: float = 120.0, **extra: Any) -> None:
        """``done``, then stay while the session delivers what is in flight, till the run ends."""
        self.flush_records()
        self.ctl("done", k, t, rejected=self.rejected, **extra)
        deadline = time.monotonic() + linger_s
        while time.monotonic() < deadline:
            for feed in self.feeds.values():  # inputs are no longer needed: keep the FIFOs
                while feed.try_recv() is not None:  # from filling (a full one holds Zenoh's
                    pass  # receive thread, and the clock's "done" behind it)
            try:
                self.check_orchestrator()
                msg = self._take(timeout=0.1)
            except queue.Empty:
                continue
            except RunError:
                return
            if msg is not None and msg.kind == "done":
                return

    def close(self) -> None:
        self._closed.set()
        try:
            self._token.undeclare()
        except Exception:
            pass


@contextlib.contextmanager
def alive_while_busy(part: Participant, k: int, t: float,
                     period_s: float = 1.0) -> Iterator[None]:
    """Tell the orchestrator every ``period_s`` [s] that this node is working on step ``k``
    while the block inside runs (a fatigue block, the recorder's table export: seconds on a
    loaded machine, more than a short run's stall timeout). Only then: a node stuck anywhere
    else is still seen as stalled."""
    done = threading.Event()

    def beat() -> None:
        while not done.wait(period_s):
            try:
                part.ctl("progress", k, t, rejected=part.rejected)
            except Exception:  # the session is closing: the main thread will say why
                return

    th = threading.Thread(target=beat, daemon=True, name=f"{part.node}-heartbeat")
    th.start()
    try:
        yield
    finally:
        done.set()
        th.join()


class StartBarrier:
    """A node's side of the start handshake before the ``start``: ``hello`` every
    :data:`HELLO_PERIOD_S`, then ``ready`` once every input was heard (else ``waiting``
    naming the silent ones, every :data:`WAITING_PERIOD_S`); RunError after ``timeout_s``."""

    def __init__(self, part: Participant, timeout_s: float, info: Mapping[str, Any]) -> None:
        now = time.monotonic()
        self.part, self.timeout_s, self.info = part, timeout_s, dict(info)
        self.deadline, self.next_send = now + timeout_s, 0.0
        self.next_waiting = now + WAITING_PERIOD_S

    def tick(self, silent: list[str]) -> float:
        """Send what is due (``silent``: the inputs not heard yet); the time to the next [s]."""
        part, now = self.part, time.monotonic()
        if now >= self.deadline:
            raise RunError(f"{part.node}: not started within {self.timeout_s:.0f} s"
                           + (f"; never heard {', '.join(silent)}" if silent else ""))
        if now >= self.next_send:
            self.next_send = now + HELLO_PERIOD_S
            part.check_orchestrator()
            part.publish_hello()
            if not silent:
                part.ctl("ready", info={"outputs": part.outputs, **self.info})
            elif now >= self.next_waiting:  # tell the orchestrator what holds this node up
                self.next_waiting = now + WAITING_PERIOD_S
                part.ctl("waiting", missing=silent)
        return max(0.0, self.next_send - now)
