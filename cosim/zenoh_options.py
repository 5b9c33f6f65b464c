"""The Zenoh session options of a command, and how its session is opened: in one place.

In the style of the zenoh-python examples' ``common.py``: a command adds the options to its
parser with :func:`add_zenoh_arguments` and opens its session with :func:`open_session`
(:func:`resolve_mode`, then :func:`open_bus`).

    --connect EP (repeatable)   endpoints to connect to (a run's, a router's)
    --listen EP (repeatable)    endpoints to listen on
    --lowlatency                Zenoh's low-latency transport (negotiated per link)
    --mode auto|peer|client     auto: a peer when the session listens, a client otherwise
    --zenoh-config FILE         a Zenoh JSON5 configuration file (TLS, access control)

A *client* gets everything through the one router or peer it connects to: a run's
orchestrator routes for its clients, and what a run's nodes send reaches a client connected to
it whether it is on this machine or another. A *peer* only gets what is sent to it directly:
a run's local nodes form an explicit mesh with gossip off (:mod:`orchestrator.local_mesh`), so
a peer connected to the orchestrator would hear nothing of them (and a peer on another machine
is not relayed by a router). A session that listens (a replay others connect to) is a peer.

:func:`add_zenoh_arguments` (all five, with the session policy above) is used by ``suscosim
tap``, ``replay`` and ``scope``, the commands that join a run from outside. A command with
session defaults of its own (``run``, ``sweep``, ``router``; ``node`` can too) adds the options
it has one at a time, with its own help text, metavar and default: :func:`add_connect_argument`,
:func:`add_listen_argument`, :func:`add_lowlatency_argument` (``negatable``: ``run``'s
``--lowlatency/--no-lowlatency``), :func:`add_mode_argument` (``choices``, ``default``),
:func:`add_config_argument`.
"""

from __future__ import annotations

import argparse
from typing import Any

MODES = ("auto", "peer", "client")
CLIENT_CONNECT_TIMEOUT_MS = 10000
"""How long a tap/replay/scope client keeps trying to reach its endpoint [ms]."""


class SessionOpenError(Exception):
    """The session could not be opened: ``reason`` (one line) and the exit ``code`` (1: the
    endpoint cannot be reached, 2: bad input such as a bad endpoint or a port in use)."""

    def __init__(self, reason: str, code: int, mode: str) -> None:
        super().__init__(reason)
        self.reason, self.code, self.mode = reason, code, mode

    def message(self, where: str) -> str:
        """The command's error line: ``cannot open a Zenoh MODE session (WHERE): REASON``."""
        return f"cannot open a Zenoh {self.mode} session ({where}): {self.reason}"


MODE_HELP = ("Zenoh session mode; auto: peer when listening, client otherwise (through the "
             "run's orchestrator or a router: a run's nodes are an explicit mesh that a peer "
             "connecting to the orchestrator does not join)")
"""The help of ``--mode`` for the commands that follow :func:`session_mode`."""
LISTEN_HELP = "endpoint to listen on (default: a free loopback port)"
CONFIG_HELP = "Zenoh JSON5 config file (TLS, access control)"


def add_connect_argument(ap: argparse.ArgumentParser, help: str, *, metavar: str | None = "EP",
                         default: list[str] | None = None) -> None:
    """``--connect EP`` (repeatable): the endpoints the session connects to (a run's, a
    router's). ``default`` None: absent gives None; ``[]``: absent gives an empty list.
    ``metavar`` None: argparse's own (``CONNECT``)."""
    ap.add_argument("--connect", action="append", metavar=metavar, default=default, help=help)


def add_listen_argument(ap: argparse.ArgumentParser, help: str = LISTEN_HELP, *,
                        metavar: str | None = "EP") -> None:
    """``--listen EP`` (repeatable): the endpoints the session listens on (absent: None)."""
    ap.add_argument("--listen", action="append", metavar=metavar, help=help)


def add_lowlatency_argument(ap: argparse.ArgumentParser, help: str, *,
                            negatable: bool = False) -> None:
    """``--lowlatency``: Zenoh's low-latency transport (negotiated per link). A flag (absent:
    False), or with ``negatable`` ``--lowlatency/--no-lowlatency`` (absent: None, the command
    decides)."""
    if negatable:
        ap.add_argument("--lowlatency", action=argparse.BooleanOptionalAction, default=None,
                        help=help)
    else:
        ap.add_argument("--lowlatency", action="store_true", help=help)


def add_mode_argument(ap: argparse.ArgumentParser, help: str = MODE_HELP, *,
                      choices: tuple[str, ...] = MODES, default: str | None = "auto") -> None:
    """``--mode``: the session mode, one of ``choices`` (see :func:`resolve_mode`)."""
    ap.add_argument("--mode", choices=list(choices), default=default, help=help)


def add_config_argument(ap: argparse.ArgumentParser) -> None:
    """``--zenoh-config FILE``: a Zenoh JSON5 configuration file (TLS, access control)."""
    ap.add_argument("--zenoh-config", help=CONFIG_HELP)


def add_zenoh_arguments(ap: argparse.ArgumentParser, *, connect_help: str,
                        lowlatency_help: str, listen_help: str = LISTEN_HELP,
                        mode_help: str = MODE_HELP) -> None:
    """Add ``--connect``, ``--listen``, ``--lowlatency``, ``--mode`` and ``--zenoh-config``
    to ``ap``, for a command that opens its session with :func:`resolve_mode` and
    :func:`open_bus` (the connect and low-latency help texts are the command's: their
    defaults differ)."""
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
    """``auto``: a peer when the session listens (others connect to it: a replay), else a
    client (everything through the one endpoint it connects to, the run's orchestrator or a
    router). Not a peer on loopback: a run's local nodes link as an explicit mesh with gossip
    off (:mod:`orchestrator.local_mesh`), so a peer connected to the orchestrator would hear
    none of them; the orchestrator routes for its clients. The endpoints in ``connect`` do not
    decide (loopback or not, the way is the same)."""
    if mode != "auto":
        return mode
    return "peer" if listen else "client"


def resolve_mode(mode: str, config_file: str | None, connect: list[str],
                 listen: list[str] | None) -> str:
    """The session mode: ``configured`` (the configuration file's own) for ``auto`` with a
    config file, else :func:`session_mode`."""
    if config_file and mode == "auto":
        return "configured"
    return session_mode(mode, connect, listen)


def apply_mode(conf: Any, mode: str, connect_timeout_ms: int = CLIENT_CONNECT_TIMEOUT_MS
               ) -> Any:
    """Make a :func:`cosim.bus.zenoh_config` a client's (no listening; keep trying to reach
    the endpoint for ``connect_timeout_ms``), or leave it a peer's; either tries again every
    0.1-0.5 s (:data:`cosim.bus.CONNECT_RETRY`: a scope started before its run must not
    connect seconds late and miss a short run's start), also with a config file's own retry."""
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
    """A :class:`cosim.bus.ZenohBus` in ``mode`` (from :func:`resolve_mode`); a client tries
    to reach its endpoint for ``connect_timeout_ms``.

    Raises :class:`SessionOpenError` with Zenoh's reason in one line (bad endpoint, port in
    use, unreachable router) instead of its exception.
    """
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
    """The bus the options of :func:`add_zenoh_arguments` (``args``) ask for, and its mode:
    :func:`resolve_mode` of ``args.mode``, then :func:`open_bus` on ``connect`` and ``listen``
    (the command's endpoints: its options with its own defaults), low-latency when
    ``args.lowlatency`` or ``lowlatency`` (e.g. the run uses it).

    ``wait`` (a tap, a scope: started before the run they watch, as often as after): a client
    chosen by ``--mode auto`` is a :class:`cosim.late_bus.LateBus`, opened as soon as its
    endpoint answers; an explicit ``--mode client`` still gives up after
    :data:`CLIENT_CONNECT_TIMEOUT_MS`.

    Raises :class:`SessionOpenError` (its :meth:`~SessionOpenError.message` is the error line).
    """
    mode = resolve_mode(args.mode, args.zenoh_config, connect, listen)
    ll = args.lowlatency or lowlatency
    if wait and mode == "client" and args.mode == "auto":
        from cosim.bus import zenoh_config
        from cosim.late_bus import LateBus

        try:  # a malformed endpoint is bad input now, not a wait forever
            zenoh_config(connect, None, mode="client")
        except Exception as exc:
            raise SessionOpenError(_reason(exc), 2, mode) from None
        return LateBus(lambda timeout_ms: open_bus(connect, None, "client", lowlatency=ll,
                                                   connect_timeout_ms=timeout_ms)), mode
    return open_bus(connect, listen, mode, lowlatency=ll,
                    config_file=args.zenoh_config), mode
