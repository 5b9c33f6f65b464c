"""The sinks' bounded window (DESIGN.md "Multi-rate"). The *sinks* (every node off the coupled
chain) take the producers' data as it comes. A sink that lags is buffered up to
``run.sink_window_s`` of simulated time (as steps: ``window``; 0: unbounded); beyond that the
plant holds the chain before its next step until the sink is back inside the window: a sink
that cannot keep up costs time, never unbounded memory. A sink's progress is what it tells the
orchestrator on its control key (the plant listens too); one that makes no progress for the
stall timeout while the chain waits ends the run with a :class:`RunError` naming it."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterable
from typing import Any

from . import keys
from .errors import RunError, WireError
from .outbox import RECORD_BATCH

DONE = 1 << 62  # a sink's step once it is done: never behind
MIN_WINDOW = 2 * RECORD_BATCH
"""The narrowest window [steps]: the recorder may be a records batch behind the chain."""


def window_steps(window_s: float, h: float) -> int:
    """``run.sink_window_s`` as steps of ``h`` (0: unbounded), at least :data:`MIN_WINDOW`."""
    return 0 if window_s <= 0 else max(MIN_WINDOW, round(window_s / h))


class SinkWindow:
    """The window of ``sinks`` for the node on ``part``, ``window`` steps wide."""

    def __init__(self, part: Any, sinks: Iterable[str], window: int, start_k: int = 0) -> None:
        self.part, self.window = part, int(window)
        self.k: dict[str, int] = {s: start_k - 1 for s in sinks} if self.window > 0 else {}
        self.held_s = 0.0  # how long the chain waited for the sinks [s] (wall)
        self._cond = threading.Condition()
        self._changed = time.monotonic()
        for s in self.k:
            part.bus.subscribe(keys.key(part.run, s, keys.CTL), self._on_ctl)

    def _on_ctl(self, key: str, raw: bytes) -> None:
        """A sink's control message (on the bus's thread)."""
        node = key.rsplit("/", 2)[-2]
        try:
            msg = self.part.open(key, raw)
        except WireError:
            return  # counted where the orchestrator takes it
        if msg.kind not in ("progress", "done") or node not in self.k:
            return
        with self._cond:
            k = DONE if msg.kind == "done" else max(self.k[node], msg.k)
            if k > self.k[node]:
                self.k[node], self._changed = k, time.monotonic()
                self._cond.notify_all()

    def _furthest(self) -> tuple[str, int]:
        node = min(self.k, key=self.k.__getitem__)
        return node, self.k[node]

    def hold(self, k: int) -> None:
        """Before step ``k``: send the records, wait while a sink is over the window behind."""
        if not self.k or min(self.k.values()) >= k - self.window:
            return
        self.part.flush_records()  # what the sinks need to catch up
        t0 = time.monotonic()
        with self._cond:
            self._changed = max(self._changed, t0)
            while True:
                node, at = self._furthest()
                if at >= k - self.window:
                    break
                now = time.monotonic()
                if now - self._changed >= self.part.stall_timeout_s:
                    raise RunError(f"{self.part.node}: the sink {node!r} is {k - 1 - at} steps "
                                   f"behind (run.sink_window_s allows {self.window}) and made "
                                   f"no progress for {self.part.stall_timeout_s:.1f} s")
                self._cond.wait(0.05)
                self._cond.release()
                try:  # an abort, or the orchestrator gone, ends the wait
                    self.part.poll_control()
                finally:
                    self._cond.acquire()
        self.held_s += time.monotonic() - t0
