"""The Zenoh session options of a command, and how its session is opened: in one place.

A command adds ``--connect``, ``--listen``, ``--lowlatency``, ``--mode auto|peer|client`` and
``--zenoh-config`` with :func:`add_zenoh_arguments` or one at a time with its own defaults,
and opens its session with :func:`open_session`. A *client* gets everything through the one
router or peer it connects to (a run's orchestrator routes for its clients); a *peer* only
what is sent to it directly (a run's local nodes are an explicit mesh with gossip off, so a
peer connected to the orchestrator hears none of them). A session that listens is a peer.
"""

from __future__ import annotations

import argparse
import threading
from collections.abc import Callable
from typing import Any

from .bus import Callback, LiveCallback

MODES = ("auto", "peer", "client")
CLIENT_CONNECT_TIMEOUT_MS = 10000  # how long a tap/replay/scope client tries [ms]


class SessionOpenError(Exception):
    """The session could not be opened: ``reason`` (one line), exit ``code`` (1: endpoint
    unreachable, 2: bad input such as a bad endpoint or a port in use)."""

    def __init__(self, reason: str, code: int, mode: str) -> None:
        super().__init__(reason)
        self.reason, self.code, self.mode = reason, code, mode

    def message(self, where: str) -> str:
        return f"cannot open a Zenoh {self.mode} session ({where}): {self.reason}"


MODE_HELP = ("Zenoh session mode; auto: peer when listening, client otherwise (through the "
             "run's orchestrator or a router: a run's nodes are an explicit mesh that a peer "
             "connecting to the orchestrator does not join)")
LISTEN_HELP = "endpoint to listen on (default: a free loopback port)"
CONFIG_HELP = "Zenoh JSON5 config file (TLS, access control)"


def add_connect_argument(ap: argparse.ArgumentParser, help: str, *, metavar: str | None = "EP",
                         default: list[str] | None = None) -> None:
    """``--connect EP`` (repeatable; absent: ``default``)."""
    ap.add_argument("--connect", action="append", metavar=metavar, default=default, help=help)


def add_listen_argument(ap: argparse.ArgumentParser, help: str = LISTEN_HELP, *,
                        metavar: str | None = "EP") -> None:
    """``--listen EP`` (repeatable; absent: None)."""
    ap.add_argument("--listen", action="append", metavar=metavar, help=help)


def add_lowlatency_argument(ap: argparse.ArgumentParser, help: str, *,
                            negatable: bool = False) -> None:
    """``--lowlatency`` (``negatable``: ``--[no-]lowlatency``, absent: None)."""
    if negatable:
        ap.add_argument("--lowlatency", action=argparse.BooleanOptionalAction, default=None,
                        help=help)
    else:
        ap.add_argument("--lowlatency", action="store_true", help=help)


def add_mode_argument(ap: argparse.ArgumentParser, help: str = MODE_HELP, *,
                      choices: tuple[str, ...] = MODES, default: str | None = "auto") -> None:
    """``--mode``: the session mode (:func:`resolve_mode`)."""
    ap.add_argument("--mode", choices=list(choices), default=default, help=help)


def add_config_argument(ap: argparse.ArgumentParser) -> None:
    ap.add_argument("--zenoh-config", help=CONFIG_HELP)


def add_zenoh_arguments(ap: argparse.ArgumentParser, *, connect_help: str,
                        lowlatency_help: str, listen_help: str = LISTEN_HELP,
                        mode_help: str = MODE_HELP) -> None:
    """All five options (the connect and low-latency help texts are the command's)."""
    add_connect_argument(ap, connect_help)
    add_listen_argument(ap, listen_help)
    add_lowlatency_argument(ap, lowlatency_help)
    add_mode_argument(ap, mode_help)
    add_config_argument(ap)


def is_loopback(ep: str) -> bool:
    """Whether a Zenoh endpoint (``tcp/127.0.0.1:7447``) is on this machine's loopback."""
    host = ep.split("/", 1)[-1].rsplit(":", 1)[0].strip("[]").split("#")[0]
    return host in ("localhost", "::1") or host.startswith("127.")


def session_mode(mode: str, connect: list[str], listen: list[str] | None) -> str:
    """``auto``: a peer when the session listens, else a client."""
    if mode != "auto":
        return mode
    return "peer" if listen else "client"


def resolve_mode(mode: str, config_file: str | None, connect: list[str],
                 listen: list[str] | None) -> str:
    """The session mode: ``configured`` (the config file's own) for ``auto`` with one."""
    if config_file and mode == "auto":
        return "configured"
    return session_mode(mode, connect, listen)


def apply_mode(conf: Any, mode: str, connect_timeout_ms: int = CLIENT_CONNECT_TIMEOUT_MS
               ) -> Any:
    """Make a :func:`cosim.bus.zenoh_config` a client's (no listening; trying to reach the
    endpoint for ``connect_timeout_ms``) or leave it a peer's; either retries at
    :data:`cosim.bus.CONNECT_RETRY`."""
    import json

    from cosim.bus import CONNECT_RETRY

    conf.insert_json5("connect/retry", json.dumps(CONNECT_RETRY))
    if mode == "client":
        conf.insert_json5("mode", '"client"')
        conf.insert_json5("listen/endpoints", "[]")
        conf.insert_json5("connect/timeout_ms", str(int(connect_timeout_ms)))
    return conf


def _reason(exc: Exception) -> str:
    """Zenoh's error in one line, without the Rust source location it ends with."""
    return " ".join(str(exc).split(" at /")[0].split())


def open_bus(connect: list[str], listen: list[str] | None, mode: str, *,
             lowlatency: bool = False, config_file: str | None = None,
             connect_timeout_ms: int = CLIENT_CONNECT_TIMEOUT_MS) -> Any:
    """A ZenohBus in ``mode``; SessionOpenError with Zenoh's reason in one line."""
    from cosim.bus import ZenohBus, zenoh_config

    try:
        conf = zenoh_config(connect, listen if mode != "client" else None,
                            lowlatency=lowlatency, config_file=config_file)
        return ZenohBus(apply_mode(conf, mode, connect_timeout_ms))
    except Exception as exc:  # zenoh.ZError: bad endpoint, port in use, unreachable router
        reason = _reason(exc)
        raise SessionOpenError(reason, 1 if "Unable to connect" in reason else 2,
                               mode) from None


def open_session(args: argparse.Namespace, connect: list[str], listen: list[str] | None, *,
                 lowlatency: bool = False, wait: bool = False) -> tuple[Any, str]:
    """The bus ``args`` ask for and its mode (SessionOpenError); ``wait``: a client chosen by
    ``--mode auto`` is a :class:`LateBus`."""
    mode = resolve_mode(args.mode, args.zenoh_config, connect, listen)
    ll = args.lowlatency or lowlatency
    if wait and mode == "client" and args.mode == "auto":
        from cosim.bus import zenoh_config

        try:  # a malformed endpoint is bad input now, not a wait forever
            zenoh_config(connect, None, mode="client")
        except Exception as exc:
            raise SessionOpenError(_reason(exc), 2, mode) from None
        return LateBus(lambda timeout_ms: open_bus(connect, None, "client", lowlatency=ll,
                                                   connect_timeout_ms=timeout_ms)), mode
    return open_bus(connect, listen, mode, lowlatency=ll,
                    config_file=args.zenoh_config), mode


ATTEMPT_TIMEOUT_MS = 1000  # one attempt to reach the endpoint [ms]; then closed is checked


class LateBus:
    """A client session that may open after its command started (a tap or scope waiting for
    a run): ``opener(timeout_ms)`` is called in a thread of its own until it succeeds or
    :meth:`close`; subscriptions asked meanwhile are declared then, queries answer nothing."""

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
        self._declare(lambda bus: bus.subscribe(keyexpr, callback))

    def watch(self, keyexpr: str, callback: LiveCallback) -> None:
        self._declare(lambda bus: bus.watch(keyexpr, callback))

    def query(self, key: str, timeout: float = 1.0) -> bytes | None:
        bus = self._bus
        return None if bus is None else bus.query(key, timeout)

    def query_all(self, key: str, timeout: float = 1.0) -> list[bytes]:
        bus = self._bus
        return [] if bus is None else bus.query_all(key, timeout)

    def linked(self) -> bool:
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
