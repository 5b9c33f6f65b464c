"""A client session that may open after its command started: a tap or scope waiting for a run.

A Zenoh client cannot open without reaching its endpoint. :class:`LateBus` opens it in a
thread of its own, trying again until it succeeds or is closed, then declares the
subscriptions and watches asked of it meanwhile; until then a query answers nothing.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from .bus import Callback, LiveCallback

ATTEMPT_TIMEOUT_MS = 1000
"""How long one attempt to reach the endpoint lasts [ms]; between two attempts the thread
checks whether it was closed."""


class LateBus:
    """A bus opened by ``opener(timeout_ms)`` in a background thread, again after every
    failure (an exception of the opener: the endpoint unreachable) until it succeeds or
    :meth:`close` is called. ``opener`` returns a :class:`cosim.bus.ZenohBus`."""

    def __init__(self, opener: Callable[[int], Any]) -> None:
        self._opener = opener
        self._lock = threading.Lock()
        self._bus: Any = None
        self._closed = threading.Event()
        self._pending: list[Callable[[Any], Any]] = []
        self._handles: list[Any] = []
        self._thread = threading.Thread(target=self._open, daemon=True, name="late-bus")
        self._thread.start()

    def _open(self) -> None:
        while not self._closed.is_set():
            try:
                bus = self._opener(ATTEMPT_TIMEOUT_MS)
            except Exception:  # not reachable yet: try again
                self._closed.wait(0.1)
                continue
            with self._lock:
                if self._closed.is_set():
                    bus.close()
                    return
                for declare in self._pending:
                    self._handles.append(declare(bus))
                self._pending.clear()
                self._bus = bus
            return

    def _declare(self, declare: Callable[[Any], Any]) -> None:
        with self._lock:
            if self._bus is None:
                self._pending.append(declare)
            else:
                self._handles.append(declare(self._bus))

    def subscribe(self, keyexpr: str, callback: Callback) -> None:
        """Subscribe now, or as soon as the session is open."""
        self._declare(lambda bus: bus.subscribe(keyexpr, callback))

    def watch(self, keyexpr: str, callback: LiveCallback) -> None:
        """Watch liveliness tokens now, or as soon as the session is open."""
        self._declare(lambda bus: bus.watch(keyexpr, callback))

    def query(self, key: str, timeout: float = 1.0) -> bytes | None:
        """The first reply to a get of ``key``; None while the session is not open."""
        bus = self._bus
        return None if bus is None else bus.query(key, timeout)

    def query_all(self, key: str, timeout: float = 1.0) -> list[bytes]:
        """Every reply to a get of ``key``; none while the session is not open."""
        bus = self._bus
        return [] if bus is None else bus.query_all(key, timeout)

    def linked(self) -> bool:
        """Whether the session is open and linked to a peer or a router."""
        bus = self._bus
        return bus is not None and bool(bus.linked())

    def close(self) -> None:
        """Stop trying (within one attempt's timeout) and close the session if it opened."""
        self._closed.set()
        self._thread.join(timeout=ATTEMPT_TIMEOUT_MS / 1000.0 + 5.0)
        with self._lock:
            bus, self._bus = self._bus, None
        if bus is not None:
            bus.close()
