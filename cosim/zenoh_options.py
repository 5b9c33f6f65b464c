"""The Zenoh session options of a command, and how its session is opened: in one place.

In the style of the zenoh-python examples' ``common.py``: a command adds the options to its
parser with :func:`add_zenoh_arguments` and opens its session with :func:`open_session`
(:func:`resolve_mode`, then :func:`open_bus`).

    --connect EP (repeatable)   endpoints to connect to (a run's, a router's)
    --listen EP (repeatable)    endpoints to listen on
    --lowlatency                Zenoh's low-latency transport (negotiated per link)
    --mode auto|peer|client     auto: a peer when every endpoint is on loopback (or the
                                session listens), a client otherwise
    --zenoh-config FILE         a Zenoh JSON5 configuration file (TLS, access control)

A *peer* joins the run's mesh on this machine and gets the data straight from the nodes; a
*client* gets everything through the one router or peer it connects to: what works from
another machine (a peer there is not relayed by a router, and the run's peers, listening on
their loopback, cannot connect back to it).

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


MODE_HELP = ("Zenoh session mode; auto: peer when listening or every endpoint is on loopback, "
             "client otherwise (through a router, from another machine)")
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
    """``auto``: a peer (joins the run's mesh directly) when every endpoint is on loopback
    or the session listens; a client (everything through the one endpoint) otherwise: a peer
    on another machine is not relayed by a router, and the run's peers, listening on their
    loopback, cannot connect back to it."""
    if mode != "auto":
        return mode
    return "peer" if listen or all(is_loopback(e) for e in connect) else "client"


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


def open_bus(connect: list[str], listen: list[str] | None, mode: str, *,
             lowlatency: bool = False, config_file: str | None = None) -> Any:
    """A :class:`cosim.bus.ZenohBus` in ``mode`` (from :func:`resolve_mode`).

    Raises :class:`SessionOpenError` with Zenoh's reason in one line (bad endpoint, port in
    use, unreachable router) instead of its exception.
    """
    from cosim.bus import ZenohBus, zenoh_config

    try:
        conf = zenoh_config(connect, listen if mode != "client" else None,
                            lowlatency=lowlatency, config_file=config_file)
        return ZenohBus(apply_mode(conf, mode))
    except Exception as exc:  # zenoh.ZError: bad endpoint, port in use, unreachable router
        reason = " ".join(str(exc).split(" at /")[0].split())
        raise SessionOpenError(reason, 1 if "Unable to connect" in reason else 2,
                               mode) from None


def open_session(args: argparse.Namespace, connect: list[str], listen: list[str] | None, *,
                 lowlatency: bool = False) -> tuple[Any, str]:
    """The bus the options of :func:`add_zenoh_arguments` (``args``) ask for, and its mode:
    :func:`resolve_mode` of ``args.mode``, then :func:`open_bus` on ``connect`` and ``listen``
    (the command's endpoints: its options with its own defaults), low-latency when
    ``args.lowlatency`` or ``lowlatency`` (e.g. the run uses it).

    Raises :class:`SessionOpenError` (its :meth:`~SessionOpenError.message` is the error line).
    """
    mode = resolve_mode(args.mode, args.zenoh_config, connect, listen)
    return open_bus(connect, listen, mode, lowlatency=args.lowlatency or lowlatency,
                    config_file=args.zenoh_config), mode
