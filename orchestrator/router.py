"""``suscosim router``: a Zenoh router in a Python process (the pip package ships no
``zenohd``), until SIGTERM or Ctrl-C. Loopback only without ``--listen`` (or one in
``--config``: ``deploy/zenoh/router.json5`` for TLS); multicast scouting off unless the file
turns it on. Exit codes: 0 stopped, 1 could not start (port in use), 2 bad arguments or file.
"""

from __future__ import annotations

import argparse
import json
import re
import signal
import sys
import threading
from pathlib import Path
from typing import Any

from cosim.zenoh_options import add_listen_argument
from orchestrator.cli_util import fail

DEFAULT_LISTEN = "tcp/127.0.0.1:7447"
DEFAULT_LEASE_MS = 2000


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return re.sub(r" at /\S+\.rs:\d+\.?", "", text).strip()


def _is_unset(conf: Any, key: str) -> bool:
    value = json.loads(conf.get_json(key))
    return value is None or isinstance(value, dict)


def router_config(listen: list[str] | None = None, config_file: str | None = None,
                  lease_ms: int = DEFAULT_LEASE_MS) -> tuple[Any, list[str]]:
    """A router's Zenoh configuration and endpoints; ValueError for a bad file or endpoint."""
    import zenoh

    try:
        conf = zenoh.Config.from_file(config_file) if config_file else zenoh.Config()
    except Exception as exc:  # zenoh raises its own error type with the parser's message
        raise ValueError(f"{config_file}: not a valid Zenoh configuration: "
                         f"{_one_line(exc)}") from exc
    conf.insert_json5("mode", '"router"')
    if _is_unset(conf, "scouting/multicast/enabled"):
        conf.insert_json5("scouting/multicast/enabled", "false")
    if listen:
        endpoints = list(listen)
    elif not _is_unset(conf, "listen/endpoints") and json.loads(conf.get_json("listen/endpoints")):
        endpoints = json.loads(conf.get_json("listen/endpoints"))
    else:
        endpoints = [DEFAULT_LISTEN]
    try:
        conf.insert_json5("listen/endpoints", json.dumps(endpoints))
    except Exception as exc:
        raise ValueError(f"listen endpoints {endpoints}: {_one_line(exc)}") from exc
    conf.insert_json5("transport/link/tx/lease", str(int(lease_ms)))
    # The admin space answers ZenohBus.flush's barrier query (#30 item 17: the last put
    # before a close was lost); read only.
    conf.insert_json5("adminspace/enabled", "true")
    conf.insert_json5("adminspace/permissions/read", "true")
    return conf, endpoints


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="suscosim router", description=__doc__.splitlines()[0])
    add_listen_argument(ap, f"endpoint to listen on (repeatable; default {DEFAULT_LISTEN}, "
                            "loopback only), e.g. tcp/0.0.0.0:7447 or tls/0.0.0.0:7447",
                        metavar="ENDPOINT")
    ap.add_argument("--config", metavar="FILE.json5",
                    help="Zenoh configuration (e.g. deploy/zenoh/router.json5: TLS, "
                         "access control)")
    ap.add_argument("--lease-ms", type=int, default=DEFAULT_LEASE_MS,
                    help=f"link lease announced to peers [ms] (default {DEFAULT_LEASE_MS})")
    args = ap.parse_args(argv)
    if args.config and not Path(args.config).is_file():
        return fail("suscosim router", f"{args.config}: no such file")
    if args.lease_ms <= 0:
        return fail("suscosim router", f"--lease-ms {args.lease_ms}: expected > 0")
    try:
        conf, endpoints = router_config(args.listen, args.config, args.lease_ms)
    except ValueError as exc:
        return fail("suscosim router", str(exc))

    import zenoh

    stop = threading.Event()
    previous = {sig: signal.signal(sig, lambda *_: stop.set())
                for sig in (signal.SIGTERM, signal.SIGINT)}
    try:
        try:
            session = zenoh.open(conf)
        except Exception as exc:  # bind failure, unreadable certificate...
            return fail("suscosim router",
                        f"cannot start on {', '.join(endpoints)}: {_one_line(exc)}", code=1)
        try:
            print(f"suscosim router: {session.info.zid()} listening on "
                  f"{', '.join(endpoints)}", flush=True)
            while not stop.wait(0.5):
                pass
        finally:
            session.close()
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    print("suscosim router: stopped", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
