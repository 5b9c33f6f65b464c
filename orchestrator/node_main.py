"""Start one node: ``suscosim node NAME --run ID [--connect ENDPOINT]``.

The node opens its own Zenoh session, fetches the resolved scenario from the orchestrator of
that run, and runs. It can live on any machine that reaches the orchestrator (or a router).
Exit codes: 0 done, 1 run error (abort, stall, dead peer), 2 bad scenario or input.
"""

from __future__ import annotations

import argparse
import faulthandler
import importlib
import logging
import signal
import sys
import traceback

from cosim.bus import ZenohBus, zenoh_config
from cosim.errors import RunError, SuscosimError
from cosim.participant import Participant

NODE_MODULES = {
    "plant": "nodes.plant.node",
    "tyre_road": "nodes.tyre_road.node",
    "controller": "nodes.controller.node",
    "recorder": "nodes.recorder.node",
    "fatigue": "nodes.fatigue.node",
}


def run_node(bus, run_id: str, name: str, scenario: dict | None = None,
             spin_s: float = 0.0) -> int:
    """Run node ``name`` on ``bus``; report errors to the orchestrator; return an exit code."""
    log = logging.getLogger(f"suscosim.{name}")
    part = Participant(bus, run_id, name, spin_s=spin_s)
    try:
        if scenario is None:
            scenario = part.fetch_scenario()
        part.stall_timeout_s = float(scenario["run"]["stall_timeout_s"])
        module = importlib.import_module(NODE_MODULES[name])
        module.run(part, scenario)
        return 0
    except SuscosimError as exc:
        if not (isinstance(exc, RunError) and "aborted by the orchestrator" in str(exc)):
            part.ctl("error", message=str(exc), exit_code=exc.exit_code)
        log.error("%s", exc)
        return exc.exit_code
    except Exception as exc:  # a bug: say where, tell the orchestrator, never hang
        log.error("internal error: %s\n%s", exc, traceback.format_exc())
        part.ctl("error", message=f"internal error: {type(exc).__name__}: {exc}", exit_code=1)
        return 1
    finally:
        try:
            part.flush_records()  # what this node computed stays recorded, even on an error
        except Exception:
            pass
        part.close()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="suscosim node", description=__doc__.splitlines()[0])
    ap.add_argument("name", choices=sorted(NODE_MODULES))
    ap.add_argument("--run", required=True, help="run id (printed by 'suscosim run')")
    ap.add_argument("--connect", action="append", default=[],
                    help="Zenoh endpoint of the orchestrator or a router, e.g. tcp/10.0.0.1:7447")
    ap.add_argument("--listen", action="append", default=None,
                    help="endpoint to listen on (default: loopback only)")
    ap.add_argument("--lowlatency", action="store_true",
                    help="Zenoh low-latency transport (negotiated per link: peers without it "
                         "still connect; the orchestrator sets it for its local nodes)")
    ap.add_argument("--zenoh-config", help="Zenoh JSON5 config file (TLS, access control)")
    ap.add_argument("--lease-ms", type=int, default=2000,
                    help="Zenoh link lease [ms]: how long peers keep this node's links when it "
                         "goes silent (default 2000; the orchestrator gives its local nodes "
                         "the run's stall timeout)")
    ap.add_argument("--spin-us", type=float, default=0.0,
                    help="poll an input this long before blocking on it [us] (the "
                         "orchestrator sets it for nodes it pins to a core)")
    ap.add_argument("--mode", choices=["client", "peer"],
                    help="Zenoh mode (default: the config file's, else client: everything "
                         "through the router or orchestrator given by --connect; the "
                         "orchestrator starts its local nodes as peers)")
    args = ap.parse_args(argv)
    if args.lease_ms <= 0:
        print(f"suscosim node: --lease-ms {args.lease_ms}: expected > 0", file=sys.stderr)
        return 2
    logging.basicConfig(level=logging.INFO, format=f"%(asctime)s {args.name}: %(message)s",
                        stream=sys.stderr)
    # a node stopped with SIGTERM (the orchestrator ending a run it holds up) says where it
    # was: every thread's stack goes to its log, then the signal ends it as before
    faulthandler.register(signal.SIGTERM, chain=True)
    try:
        bus = ZenohBus(zenoh_config(args.connect, args.listen, args.lowlatency,
                                    lease_ms=args.lease_ms, config_file=args.zenoh_config,
                                    mode=args.mode, default_mode="client"))
    except Exception as exc:  # unreachable router, bad config file or certificate
        text = " ".join(str(exc).split())
        print(f"suscosim node {args.name}: cannot open the Zenoh session "
              f"(--connect {' '.join(args.connect) or '-'}): {text}", file=sys.stderr)
        return 1
    try:
        return run_node(bus, args.run, args.name, spin_s=args.spin_us * 1e-6)
    finally:
        bus.close()


if __name__ == "__main__":
    sys.exit(main())
