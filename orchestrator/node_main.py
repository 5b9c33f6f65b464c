"""``suscosim node NAME --run ID [--connect ENDPOINT]``: one node in its own Zenoh session, on
any machine that reaches the run's orchestrator (it fetches the scenario from it). The run key:
``SUSCOSIM_RUN_KEY``, else derived from ``--key-file``/``SUSCOSIM_KEY_FILE``/``SUSCOSIM_KEY``.
Exit codes: 0 done, 1 run error (abort, stall, dead peer), 2 bad scenario, input or no key.
"""

from __future__ import annotations

import argparse
import faulthandler
import inspect
import logging
import os
import signal
import sys
import traceback
from collections.abc import Callable
from contextlib import suppress
from typing import Any

from cosim import node_kinds as nk
from cosim import zenoh_options as zo
from cosim.auth import ENV_KEY_FILE, RunKey, run_key_from_env
from cosim.bus import ZenohBus, zenoh_config
from cosim.errors import InputLate, RunError, SuscosimError
from cosim.participant import Participant
from cosim.stepped import run_stepped

from .cli_util import fail

NODE_MODULES: dict[str, str] = nk.entries()  # node kind -> its module (the names node takes)


def node_callable(name: str, scenario: dict[str, Any]) -> Callable[[Participant], None]:
    """The implementation ``[nodes]`` picks: a function, or a class stepped as a node."""
    impl = nk.implementation(name, scenario)
    obj = nk.load(impl.entry, f"{nk.SECTION}.{name}")
    if inspect.isclass(obj):
        return lambda part: run_stepped(obj, part, scenario, name)
    return lambda part: obj(part, scenario)


def run_node(bus, run_id: str, name: str, scenario: dict | None = None,
             spin_s: float = 0.0, key: bytes | None = None, nonce: bytes = b"") -> int:
    """Run node ``name`` on ``bus`` (errors told to the orchestrator); the exit code."""

    log = logging.getLogger(f"suscosim.{name}")
    try:
        auth = RunKey(key if key is not None else run_key_from_env(run_id))
    except SuscosimError as exc:  # no key: nothing it could say would be believed
        log.error("%s", exc)
        return exc.exit_code
    part = Participant(bus, run_id, name, spin_s=spin_s, auth=auth)
    try:
        if scenario is None:
            scenario = part.fetch_scenario()
        elif nonce:
            part.bind(nonce)
        run = scenario["run"]
        part.stall_timeout_s = float(run["stall_timeout_s"])
        part.expect_start = {"n_steps": run.get("n_steps"), "h": run.get("h"),
                             "nodes": list(run.get("nodes", []))}
        node_callable(name, scenario)(part)
        return 0
    except SuscosimError as exc:
        if not (isinstance(exc, RunError) and "aborted by the orchestrator" in str(exc)):
            late: dict[str, Any] = {"late": exc.late} if isinstance(exc, InputLate) else {}
            part.ctl("error", message=str(exc), exit_code=exc.exit_code, **late)
        log.error("%s", exc)
        return exc.exit_code
    except Exception as exc:  # a bug: say where, tell the orchestrator, never hang
        log.error("internal error: %s\n%s", exc, traceback.format_exc())
        part.ctl("error", message=f"internal error: {type(exc).__name__}: {exc}", exit_code=1)
        return 1
    finally:
        with suppress(Exception):
            part.flush_records()  # what this node computed stays recorded, even on an error
        part.close()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="suscosim node", description=__doc__.splitlines()[0])
    ap.add_argument("name", choices=sorted(NODE_MODULES))
    ap.add_argument("--run", required=True, help="run id (printed by 'suscosim run')")
    zo.add_connect_argument(ap, "Zenoh endpoint of the orchestrator or a router, e.g. "
                                "tcp/10.0.0.1:7447", metavar=None, default=[])
    zo.add_listen_argument(ap, "endpoint to listen on (default: loopback only)", metavar=None)
    zo.add_lowlatency_argument(ap, "Zenoh low-latency transport (negotiated per link; the "
                                   "orchestrator sets it for its local nodes)")
    zo.add_config_argument(ap)
    ap.add_argument("--gossip", action=argparse.BooleanOptionalAction, default=True,
                    help="find the run's other peers through the endpoints connected to "
                         "(default); --no-gossip: link only to --connect and to who connects "
                         "to --listen (the orchestrator's explicit mesh of its local nodes)")
    ap.add_argument("--key-file",
                    help="file holding the secret the run key is derived from (mode 0600, "
                         f"e.g. RUN_DIR/run.key; default ${ENV_KEY_FILE})")
    ap.add_argument("--lease-ms", type=int, default=2000,
                    help="Zenoh link lease [ms]: how long peers keep this node's links when it "
                         "goes silent (default 2000)")
    ap.add_argument("--spin-us", type=float, default=0.0,
                    help="poll an input this long before blocking on it [us] (the "
                         "orchestrator sets it for nodes it pins to a core)")
    zo.add_mode_argument(ap, "Zenoh mode (default: the config file's, else client: everything "
                             "through --connect)", choices=("client", "peer"), default=None)
    args = ap.parse_args(argv)
    if args.lease_ms <= 0:
        return fail("suscosim node", f"--lease-ms {args.lease_ms}: expected > 0")
    if args.key_file:  # read where run_node looks (the environment), like the default
        os.environ[ENV_KEY_FILE] = args.key_file
        os.environ.pop("SUSCOSIM_RUN_KEY", None)
    logging.basicConfig(level=logging.INFO, format=f"%(asctime)s {args.name}: %(message)s",
                        stream=sys.stderr)
    # a node stopped with SIGTERM (the orchestrator ending a run it holds up) says where it
    # was: every thread's stack goes to its log, then the signal ends it as before
    faulthandler.register(signal.SIGTERM, chain=True)
    try:
        bus = ZenohBus(zenoh_config(args.connect, args.listen, args.lowlatency,
                                    lease_ms=args.lease_ms, config_file=args.zenoh_config,
                                    mode=args.mode, default_mode="client", gossip=args.gossip))
    except Exception as exc:  # unreachable router, bad config file or certificate
        text = " ".join(str(exc).split())
        print(f"suscosim node {args.name}: cannot open the Zenoh session "
              f"(--connect {' '.join(args.connect) or '-'}): {text}", file=sys.stderr)
        return 1
    try:
        return run_node(bus, args.run, args.name, spin_s=args.spin_us * 1e-6)
    finally:
        bus.close()
