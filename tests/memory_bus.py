"""An in-memory bus for the tests: the verbs of :class:`cosim.bus.Bus` without a network
(it was the product's in-memory bus of the threaded monolithic mode, replaced by the
one-process engine, orchestrator/inprocess.py, issue #41). Delivery is synchronous in the
publisher's thread, in publication order."""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable
from typing import Any

from cosim.bus import Callback, LiveCallback, keyexpr_matches


class MemoryBus:
    """In-process bus: same verbs as :class:`cosim.bus.ZenohBus`, no network."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._subs: list[tuple[str, Callback]] = []
        self._routes: dict[str, list[Callback]] = {}
        self._watchers: list[tuple[str, LiveCallback]] = []
        self._tokens: set[str] = set()
        self._served: dict[str, Callable[[], bytes]] = {}

    def publisher(self, key: str) -> Callable[[bytes], None]:
        return lambda payload: self.put(key, payload)

    def put(self, key: str, payload: bytes) -> None:
        with self._lock:
            targets = self._routes.get(key)
            if targets is None:  # matched once per key, until the subscriptions change
                targets = self._routes[key] = [cb for kx, cb in self._subs
                                               if keyexpr_matches(kx, key)]
        for cb in targets:
            cb(key, payload)

    def subscribe(self, keyexpr: str, callback: Callback) -> Any:
        with self._lock:
            self._subs.append((keyexpr, callback))
            self._routes.clear()
        return (keyexpr, callback)

    def feed(self, key: str, capacity: int = 1024) -> _MemoryFeed:
        feed = _MemoryFeed()
        self.subscribe(key, lambda _k, raw: feed.queue.put(raw))
        return feed

    def token(self, key: str) -> Any:
        self._set_token(key, True)
        return _MemoryToken(self, key)

    def _drop_token(self, key: str) -> None:
        self._set_token(key, False)

    def _set_token(self, key: str, alive: bool) -> None:
        """Declare (``alive``) or drop the token ``key``; tell the watchers that match it (the
        ones watching at the change: their list is taken under the same lock)."""
        with self._lock:
            if alive:
                self._tokens.add(key)
            else:
                self._tokens.discard(key)
            targets = [cb for kx, cb in self._watchers if keyexpr_matches(kx, key)]
        for cb in targets:
            cb(key, alive)

    def watch(self, keyexpr: str, callback: LiveCallback) -> Any:
        with self._lock:
            self._watchers.append((keyexpr, callback))
            alive = [k for k in self._tokens if keyexpr_matches(keyexpr, k)]
        for k in alive:
            callback(k, True)
        return (keyexpr, callback)

    def serve(self, key: str, reply: Callable[[], bytes]) -> Any:
        with self._lock:
            self._served[key] = reply
        return key

    def query(self, key: str, timeout: float = 1.0) -> bytes | None:
        with self._lock:
            reply = self._served.get(key)
        return reply() if reply else None

    def query_all(self, key: str, timeout: float = 1.0) -> list[bytes]:
        raw = self.query(key, timeout)
        return [] if raw is None else [raw]

    def alive(self, keyexpr: str, timeout: float = 1.0) -> list[str]:
        with self._lock:
            return sorted(k for k in self._tokens if keyexpr_matches(keyexpr, k))

    def close(self) -> None:
        pass


class _MemoryFeed:
    """The in-memory twin of :class:`_ZenohFeed` (unbounded)."""

    def __init__(self) -> None:
        self.queue: queue.SimpleQueue[bytes] = queue.SimpleQueue()

    def recv(self) -> bytes:
        return self.queue.get()

    def try_recv(self) -> bytes | None:
        try:
            return self.queue.get_nowait()
        except queue.Empty:
            return None

    def wake(self) -> None:
        self.queue.put(b"")


class _MemoryToken:
    def __init__(self, bus: MemoryBus, key: str) -> None:
        self.bus, self.key = bus, key

    def undeclare(self) -> None:
        self.bus._drop_token(self.key)
