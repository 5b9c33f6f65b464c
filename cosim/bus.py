"""The bus: a thin layer over a Zenoh session (the tests' in-memory twin: tests/memory_bus.py).

Callbacks receive ``(key: str, payload: bytes)`` on the bus's own thread: they only hand the
bytes over, never block. A feed (the lock-step inputs) is read by the node's own thread.
Default transport: Zenoh in peer mode, listening on loopback only, multicast scouting off;
peers find each other by gossip, or link as an explicit mesh (``gossip=False``).
"""

from __future__ import annotations

import json
import logging
import threading
import time
from collections.abc import Callable, Iterable
from typing import Any, Protocol

log = logging.getLogger("suscosim.bus")

Callback = Callable[[str, bytes], None]
LiveCallback = Callable[[str, bool], None]


class Feed(Protocol):
    """A lock-step input: ``recv`` blocks (``b""`` after ``wake``), ``try_recv`` does not."""

    def recv(self) -> bytes: ...
    def try_recv(self) -> bytes | None: ...
    def wake(self) -> None: ...


class Bus(Protocol):
    """What node code, the clock and the runner use of a bus (:class:`ZenohBus`)."""

    def publisher(self, key: str) -> Callable[[bytes], None]: ...
    def put(self, key: str, payload: bytes) -> None: ...
    def subscribe(self, keyexpr: str, callback: Callback) -> Any: ...
    def feed(self, key: str, capacity: int = 1024) -> Feed: ...
    def token(self, key: str) -> Any: ...
    def watch(self, keyexpr: str, callback: LiveCallback) -> Any: ...
    def serve(self, key: str, reply: Callable[[], bytes]) -> Any: ...
    def query(self, key: str, timeout: float = 1.0) -> bytes | None: ...
    def query_all(self, key: str, timeout: float = 1.0) -> list[bytes]: ...
    def alive(self, keyexpr: str, timeout: float = 1.0) -> list[str]: ...
    def close(self) -> None: ...


LOOPBACK_LISTEN = "tcp/127.0.0.1:0"


def free_loopback_endpoint() -> str:
    """A TCP endpoint on loopback with a port that is free right now."""
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp/127.0.0.1:{s.getsockname()[1]}"


CALLBACK_DRAIN_TIMEOUT = 5.0
"""How long :meth:`ZenohBus.close` waits at most for its callbacks' threads to deliver [s]."""

CLIENT_CONNECT_TIMEOUT_MS = 30000
"""How long a client session keeps trying to reach its router before giving up [ms]."""

NODE_RUNTIME = "(rx: (handover: net), acc: (handover: net))"
"""Zenoh's runtimes in a run's local node processes (the ``ZENOH_RUNTIME`` the orchestrator
gives them; one set in its own environment wins): the receive and accept runtimes handed
over to the network runtime's one worker. A message is then read and delivered by the thread
its socket woke; with Zenoh's default (separate runtimes, two receive workers) each message
woke two or three threads in turn, on the receiver's core (#41: a traced Ch 6 step, 4 -> 1
wake-ups a message; ``python -m bench overhead``: corner + live fatigue +9 %)."""

CONNECT_RETRY = {"period_init_ms": 100, "period_max_ms": 500, "period_increase_factor": 1.5}
"""How often a session retries an endpoint it could not reach (Zenoh's own, 1 s doubling to
4 s, left a tap opened just before its run unconnected for seconds)."""


def _unset(conf: Any, key: str) -> bool:
    """True when ``key`` still holds Zenoh's own default (null, or a per-mode map)."""
    value = json.loads(conf.get_json(key))
    return value is None or isinstance(value, dict)


def zenoh_config(
    connect: Iterable[str] = (),
    listen: Iterable[str] | None = None,
    lowlatency: bool = False,
    lease_ms: int = 2000,
    config_file: str | None = None,
    mode: str | None = None,
    default_mode: str = "peer",
    gossip: bool = True,
) -> Any:
    """A Zenoh configuration for a suscosim participant. ``connect`` endpoints are added to
    the ``config_file``'s own (a Zenoh JSON5 file: TLS, access control; its mode, endpoints and
    scouting are kept unless given here); ``listen`` defaults to the file's, else a free
    loopback port (clients do not listen). ``lowlatency``: Zenoh's low-latency transport (a
    put writes to the socket from the calling thread); peers then connect only from the
    greater Zenoh id (two peers opening such a link to each other at once both failed).
    ``lease_ms`` bounds how fast a partitioned node is seen as gone (Zenoh's default: 10 s).
    ``mode`` ``"client"``: everything through the router or peer it connects to (Zenoh >= 1.9
    routers do not relay between peers); default the file's, else ``default_mode``.
    ``gossip`` False: a session of a run's explicit mesh (no link states sent or forwarded).
    """
    import zenoh

    conf = zenoh.Config.from_file(config_file) if config_file else zenoh.Config()
    mode = mode or json.loads(conf.get_json("mode")) or default_mode
    conf.insert_json5("mode", json.dumps(mode))
    if _unset(conf, "scouting/multicast/enabled"):
        conf.insert_json5("scouting/multicast/enabled", "false")
    if mode != "client" and (listen or _unset(conf, "listen/endpoints")):
        conf.insert_json5("listen/endpoints", json.dumps(list(listen or [LOOPBACK_LISTEN])))
    own = [] if _unset(conf, "connect/endpoints") else json.loads(
        conf.get_json("connect/endpoints"))
    conf.insert_json5("connect/endpoints", json.dumps(own + [c for c in connect
                                                             if c not in own]))
    if json.loads(conf.get_json("connect/retry")) is None:  # a config file's own is kept
        conf.insert_json5("connect/retry", json.dumps(CONNECT_RETRY))
    if mode == "client" and _unset(conf, "connect/timeout_ms"):
        conf.insert_json5("connect/timeout_ms", str(CLIENT_CONNECT_TIMEOUT_MS))
    conf.insert_json5("transport/link/tx/lease", str(int(lease_ms)))
    if not gossip:
        conf.insert_json5("scouting/gossip/enabled", "false")
    if lowlatency:
        conf.insert_json5("scouting/gossip/autoconnect_strategy",
                          '{peer: {to_router: "always", to_peer: "greater-zid"}}')
        conf.insert_json5("transport/unicast/lowlatency", "true")
        conf.insert_json5("transport/unicast/qos/enabled", "false")
    elif not config_file:  # a user's config file decides for itself
        # one priority only: one lane instead of eight saves CPU (negotiated per link)
        conf.insert_json5("transport/unicast/qos/enabled", "false")
    if lowlatency and not config_file:
        # no shared-memory transport for a node's low-latency session: suscosim puts no SHM
        # buffers, and with it on each session runs Zenoh's real-time SHM watchdog threads,
        # waking on the nodes' cores ~130 times a second (#41). Not for universal sessions:
        # without SHM a client's burst put right before its close lost its tail through a
        # router (tests/test_bus_flush.py; a low-latency put is in the socket when it returns)
        conf.insert_json5("transport/shared_memory/enabled", "false")
    return conf


class ZenohBus:
    """A Zenoh session with suscosim's defaults (reliable, blocking congestion control)."""

    def __init__(self, config: Any) -> None:
        import zenoh

        self._z = zenoh
        self.session = zenoh.open(config)
        self._keep: list[Any] = []
        self._drained: list[threading.Event] = []

    def _handler(self, fn: Callable[[Any], None]) -> Any:
        """``fn`` as a Zenoh callback whose ``drop`` says its thread has delivered the last:
        :meth:`close` waits for it (a process exiting while that thread waited for the GIL
        in Zenoh's frames died of SIGABRT at interpreter exit)."""
        drained = threading.Event()
        self._drained.append(drained)
        return self._z.handlers.Callback(fn, drop=drained.set)

    def publisher(self, key: str) -> Callable[[bytes], None]:
        pub = self.session.declare_publisher(
            key,
            congestion_control=self._z.CongestionControl.BLOCK,
            reliability=self._z.Reliability.RELIABLE,
            express=True,
        )
        self._keep.append(pub)
        return pub.put

    def put(self, key: str, payload: bytes) -> None:
        self.session.put(key, payload, congestion_control=self._z.CongestionControl.BLOCK)

    def subscribe(self, keyexpr: str, callback: Callback) -> Any:
        def on_sample(sample: Any) -> None:
            callback(str(sample.key_expr), sample.payload.to_bytes())

        sub = self.session.declare_subscriber(keyexpr, self._handler(on_sample))
        self._keep.append(sub)
        return sub

    def feed(self, key: str, capacity: int = 1024) -> _ZenohFeed:
        feed = _ZenohFeed(self, key, capacity)
        self._keep.append(feed)
        return feed

    def token(self, key: str) -> Any:
        tok = self.session.liveliness().declare_token(key)
        self._keep.append(tok)
        return tok

    def watch(self, keyexpr: str, callback: LiveCallback) -> Any:
        def on_sample(sample: Any) -> None:
            callback(str(sample.key_expr), sample.kind == self._z.SampleKind.PUT)

        sub = self.session.liveliness().declare_subscriber(keyexpr, self._handler(on_sample),
                                                           history=True)
        self._keep.append(sub)
        return sub

    def serve(self, key: str, reply: Callable[[], bytes]) -> Any:
        def on_query(query: Any) -> None:
            query.reply(key, reply())

        q = self.session.declare_queryable(key, self._handler(on_query))
        self._keep.append(q)
        return q

    def query(self, key: str, timeout: float = 1.0) -> bytes | None:
        for r in self.session.get(key, timeout=timeout):
            if r.ok is not None:
                return r.ok.payload.to_bytes()
        return None

    def query_all(self, key: str, timeout: float = 1.0) -> list[bytes]:
        """Every reply to a query on ``key``, none consolidated away (a rogue queryable must
        not shadow the orchestrator's: the caller picks the one it can verify)."""
        z = self._z
        return [r.ok.payload.to_bytes() for r in self.session.get(
            key, timeout=timeout, target=z.QueryTarget.ALL,
            consolidation=z.ConsolidationMode.NONE) if r.ok is not None]

    def alive(self, keyexpr: str, timeout: float = 1.0) -> list[str]:
        """The liveliness tokens matching ``keyexpr`` declared on the bus right now."""
        return [str(r.ok.key_expr) for r in
                self.session.liveliness().get(keyexpr, timeout=timeout) if r.ok is not None]

    def linked(self) -> bool:
        """Whether this session has a link to a peer or a router now."""
        info = self.session.info
        return bool(info.peers_zid() or info.routers_zid())

    def wait_linked(self, timeout: float = 10.0) -> bool:
        """Whether this session got a link within ``timeout`` [s] (before, a put meets nobody)."""
        deadline = time.monotonic() + timeout
        while not self.linked():
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.02)
        return True

    def flush(self, timeout: float = 1.0) -> int:
        """Wait until every router this session is connected to has routed what we sent (a
        query to ``@/<router zid>/router`` travels on the same FIFO link and lane as our puts;
        needs a router with ``adminspace`` read, as ``suscosim router``'s; else the wait ends
        at ``timeout`` [s]); the number of routers that replied."""
        answered = 0
        try:
            for zid in list(self.session.info.routers_zid()):
                replies = self.session.get(f"@/{zid}/router", timeout=timeout)
                answered += any(r.ok is not None for r in replies)
        except Exception:  # a session already closing: nothing left to flush
            pass
        return answered

    def close(self) -> None:
        for obj in reversed(self._keep):
            try:
                obj.undeclare()
            except Exception:  # already gone with a closing session
                pass
        self._keep.clear()
        self.session.close()  # type: ignore[no-untyped-call]  # zenoh's stub lacks a return type
        deadline = time.monotonic() + CALLBACK_DRAIN_TIMEOUT
        for drained in self._drained:  # the callbacks' threads have delivered their last
            drained.wait(max(0.0, deadline - time.monotonic()))
        self._drained.clear()


class _ZenohFeed:
    """A subscriber whose samples wait in a bounded FIFO (a full one holds the sender back)."""

    def __init__(self, bus: ZenohBus, key: str, capacity: int) -> None:
        z = bus._z
        self._sub = bus.session.declare_subscriber(key, z.handlers.FifoChannel(capacity))
        self._session, self._key, self._local = bus.session, key, z.Locality.SESSION_LOCAL

    def recv(self) -> bytes:  # blocks without holding the GIL
        return self._sub.recv().payload.to_bytes()

    def try_recv(self) -> bytes | None:
        sample = self._sub.try_recv()
        return None if sample is None else sample.payload.to_bytes()

    def wake(self) -> None:  # a put that never leaves this session
        self._session.put(self._key, b"", allowed_destination=self._local)

    def undeclare(self) -> None:
        self._sub.undeclare()  # type: ignore[no-untyped-call]  # zenoh's stub: no return type


def _chunks_match(pattern: list[str], key: list[str]) -> bool:
    if not pattern:
        return not key
    head, rest = pattern[0], pattern[1:]
    if head == "**":
        return any(_chunks_match(rest, key[i:]) for i in range(len(key) + 1))
    if not key:
        return False
    return (head == "*" or head == key[0]) and _chunks_match(rest, key[1:])


def keyexpr_matches(keyexpr: str, key: str) -> bool:
    """Zenoh key-expression matching for ``*`` (one chunk) and ``**`` (any chunks)."""
    return _chunks_match(keyexpr.split("/"), key.split("/"))
