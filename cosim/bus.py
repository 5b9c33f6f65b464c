"""The bus: a thin layer over a Zenoh session (the tests have an in-memory twin with the same
verbs, ``tests/memory_bus.py``; the one-process engine needs no bus, orchestrator/inprocess.py).

The verbs:
``publisher(key)``, ``subscribe(keyexpr, callback)``, ``feed(key)`` (a subscriber read from
its own FIFO), ``token(key)`` (liveliness), ``watch(keyexpr, callback)`` (liveliness changes),
``serve(key, reply)`` / ``query(key)`` / ``query_all(key)``, ``alive(keyexpr)`` (the live
tokens now).

Callbacks receive ``(key: str, payload: bytes)`` and run on the bus's own thread: they must
only hand the bytes over (to a queue), never block. A feed is for the lock-step inputs: the
node's thread blocks in ``feed.recv()`` and Zenoh's receive thread hands it the message
directly, without a Python callback thread in between; ``feed.wake()`` (from any thread)
makes a blocked ``recv()`` return an empty payload.

Default transport is embedded: Zenoh in peer mode, listening on loopback only, multicast
scouting off. Peers find each other through the endpoint they connect to (gossip), or, a
run's local nodes, link as an explicit mesh with gossip off (``gossip=False``).
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
    """A lock-step input read by the node's own thread (:meth:`Bus.feed`)."""

    def recv(self) -> bytes:
        """The next message; blocks (``b""`` after :meth:`wake`)."""

    def try_recv(self) -> bytes | None:
        """The next message, or None if none is waiting."""

    def wake(self) -> None:
        """Make a blocked :meth:`recv` return ``b""``."""


class Bus(Protocol):
    """What node code, the clock and the runner use of a bus: :class:`ZenohBus` implements
    it (the verbs of the module docstring)."""

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
"""How long :meth:`ZenohBus.close` waits, at most, for its callbacks' threads to deliver what
they had received [s] (a tap's callback queues a sample in microseconds)."""

CLIENT_CONNECT_TIMEOUT_MS = 30000
"""How long a client session keeps trying to reach its router before giving up [ms]."""

CONNECT_RETRY = {"period_init_ms": 100, "period_max_ms": 500, "period_increase_factor": 1.5}
"""How often a session retries an endpoint it could not reach. Zenoh's own (1 s, doubling to
4 s) left a session opened a moment before the run listened unconnected for up to 4 s: a tap
or a test that queried the run then met nobody (#30; CI failed on it twice). A retry to a
dead loopback port costs a refused SYN."""


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
    """A Zenoh configuration for a suscosim participant.

    Args:
        connect: endpoints to connect to (the orchestrator's, or a router's), e.g.
            ``["tcp/192.168.1.10:7447"]``; added to the config file's own.
        listen: endpoints to listen on; default the config file's, else loopback only on a
            free port. Clients do not listen.
        lowlatency: Zenoh's low-latency transport: a put writes to the socket from the
            calling thread instead of waking a transmit thread (~15 % more coupled steps per
            second). Negotiated per link: a peer without it (a plain tap) still connects.
            Peers then connect to each other only from the greater Zenoh id (``greater-zid``):
            two peers opening a low-latency link to each other at once both failed, about
            one start in four.
        lease_ms: how long a silent peer is kept; bounds how fast a partitioned node is seen
            as gone (Zenoh's default is 10 s).
        config_file: a Zenoh JSON5 configuration file to start from (TLS, access control);
            its mode, endpoints and scouting settings are kept unless given here.
        mode: ``"peer"`` (the embedded mesh: sessions connect to each other directly) or
            ``"client"`` (every message goes through the router or peer it connects to; what a
            node on another machine uses, since Zenoh >= 1.9 routers do not relay between two
            peers). Default: the config file's mode, else ``default_mode``.
        default_mode: the mode when neither ``mode`` nor the config file gives one.
        gossip: False for a session of a run's explicit mesh
            (:class:`orchestrator.local_mesh.LocalMesh`): it links to the endpoints it is
            given and to those that connect to it, and sends and forwards no link states.
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
        # No priority lanes: suscosim sends one priority only, and one lane instead of
        # eight saves ~10-15 % CPU per coupled step (python -m bench throughput). Peers with
        # QoS on (a plain tap, a default router) still connect: QoS is negotiated per link.
        conf.insert_json5("transport/unicast/qos/enabled", "false")
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
        """``fn`` as a Zenoh callback that says when it is done: Zenoh runs a Python callback
        in a Python thread of its own, which may still be delivering what it had received
        when its subscriber is undeclared; ``drop`` is called once it has delivered the
        last. :meth:`close` waits for it: a process that exited while that thread still
        waited for the GIL in Zenoh's frames aborted at interpreter exit ("FATAL: exception
        not rethrown": Python ends such a thread with a forced unwind, which the frames'
        ``catch_unwind`` stops). Seen as a tap that printed its result, then died of SIGABRT
        (CI, and 3 of 89 taps of a live run; 0 of 265 with this)."""
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
        """Every reply to a query on ``key`` (a rogue queryable may answer too: the caller
        picks the one it can verify). Every matching queryable is asked and no reply is
        consolidated away: by default Zenoh asks the best-matching one and keeps one reply
        per key, so a rogue queryable behind the orchestrator (one of its clients) could
        shadow the orchestrator's own reply on the same key."""
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
        """Wait until this session has a link to a peer or a router [timeout in s]: a put,
        subscription or query before then meets nobody. True when linked."""
        import time

        deadline = time.monotonic() + timeout
        while True:
            if self.linked():
                return True
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.02)

    def flush(self, timeout: float = 1.0) -> int:
        """Wait until every router this session is connected to has routed what we sent.

        A query travels on the same reliable, FIFO link and priority lane (``Priority.DATA``)
        as our puts, so a router's admin-space reply to ``@/<router zid>/router`` arrives only
        after the router has taken every earlier message off the link and queued it to its
        subscribers. It needs a router with ``adminspace`` read enabled (``suscosim router``
        enables it) whose access control lets the query in and the reply out; the shipped
        ``deploy/zenoh/router.json5`` does neither (when it let the query in, the reply was
        held back: 0 replies, the query ended in ~1 ms). Without a reply the
        wait ends at ``timeout`` [s] or when the query ends. Returns the number of routers
        that replied.

        :meth:`close` does not call it: Zenoh's own close already writes what the session's
        transmission queue holds before the link goes (zenoh-transport, the link's tx task
        drains its pipeline), and the abort the kill test's tap "missed" (#30 item 17) had
        reached it every time: the tap lost its own line (docs/deployment.md).
        """
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
    """A subscriber on one key whose samples wait in a bounded FIFO (Zenoh's ``FifoChannel``)
    until the node's thread takes them; a full FIFO holds the sender back (lock-step
    producers are never more than a few steps ahead)."""

    def __init__(self, bus: ZenohBus, key: str, capacity: int) -> None:
        z = bus._z
        self._sub = bus.session.declare_subscriber(key, z.handlers.FifoChannel(capacity))
        self._session, self._key, self._local = bus.session, key, z.Locality.SESSION_LOCAL

    def recv(self) -> bytes:
        """The next message (blocks, without holding the GIL)."""
        return self._sub.recv().payload.to_bytes()

    def try_recv(self) -> bytes | None:
        """The next message, or None if none is waiting."""
        sample = self._sub.try_recv()
        return None if sample is None else sample.payload.to_bytes()

    def wake(self) -> None:
        """Make a blocked :meth:`recv` return ``b""`` (a put that never leaves this session)."""
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
