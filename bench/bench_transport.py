"""Coupled steps per second of the Chapter 3 run over different transports.

    python bench/bench_transport.py [--t-end 2.0] [--h 0.001] [--repeat 3] [--out DIR]

Transports (every one a real ``suscosim run`` with real node processes):

* ``loopback peers``: the embedded default, every session a Zenoh peer on loopback;
* ``router, peers``: ``suscosim router`` on loopback and ``suscosim run --connect`` to it: the
  orchestrator's nodes are peers and still meet directly on loopback (the router is joined,
  but most messages do not cross it);
* ``router, all clients``: the four nodes started alone (``suscosim node``, Zenoh clients of
  the router), orchestrator ``--external`` for all: every message crosses the router;
* ``namespaces``: three Linux network namespaces joined by veth pairs (root only): router in
  one, the plant node (client) in another, orchestrator and the other nodes in a third, as in
  ``tests/integration/test_netns.py``.

Prints a markdown table: median and best coupled steps/s over ``--repeat`` runs (the clock's
steps / run wall time, start-up excluded). Timing is measured here, never asserted in tests.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cosim import channels as ch  # noqa: E402
from cosim.bus import free_loopback_endpoint  # noqa: E402

SCENARIO = ROOT / "scenarios" / "ch3_step_quarter_car.toml"
ENV = dict(os.environ, PYTHONPATH=str(ROOT), PYTHONUNBUFFERED="1")


def _cli(*args: str, prefix: list[str] | None = None, **kw) -> subprocess.Popen:
    argv = [*(prefix or []), sys.executable, "-m", "orchestrator", *args]
    return subprocess.Popen(argv, cwd=ROOT, env=ENV, text=True, **kw)


def _run(out: Path, run_id: str, base: list[str], *extra: str,
         prefix: list[str] | None = None) -> float:
    """One ``suscosim run``; its coupled steps/s from summary.json."""
    p = _cli("run", str(SCENARIO), "--quiet", "--out", str(out), "--set", f'run.id="{run_id}"',
             *base, *extra, prefix=prefix, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    stdout, stderr = p.communicate(timeout=600)
    if p.returncode != 0:
        raise RuntimeError(f"run {run_id} failed: {stdout}{stderr}")
    return float(json.loads((out / "summary.json").read_text())["steps_per_s"])


def _router(ep: str, prefix: list[str] | None = None) -> subprocess.Popen:
    r = _cli("router", "--listen", ep, prefix=prefix, stdout=subprocess.PIPE,
             stderr=subprocess.PIPE)
    line = r.stdout.readline()
    if "listening on" not in line:
        raise RuntimeError(f"router did not start: {line}{r.stderr.read()}")
    return r


def _stop(*procs: subprocess.Popen, grace_s: float = 15.0) -> None:
    """SIGTERM every process (an ended one ignores it), then SIGKILL those still running
    ``grace_s`` seconds later: one grace period for them all, not one each."""
    for p in procs:
        p.terminate()
    deadline = time.monotonic() + grace_s
    while any(p.poll() is None for p in procs) and time.monotonic() < deadline:
        time.sleep(0.05)
    for p in procs:
        if p.poll() is None:
            p.kill()
        p.wait()


def loopback_peers(out: Path, run_id: str, base: list[str]) -> float:
    return _run(out, run_id, base)


def router_peers(out: Path, run_id: str, base: list[str]) -> float:
    ep = free_loopback_endpoint()
    r = _router(ep)
    try:
        return _run(out, run_id, base, "--connect", ep)
    finally:
        _stop(r)


def router_clients(out: Path, run_id: str, base: list[str]) -> float:
    ep = free_loopback_endpoint()
    r = _router(ep)
    nodes = []
    try:
        for n in ch.NODES:
            nodes.append(_cli("node", n, "--run", run_id, "--connect", ep,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        ext = [a for n in ch.NODES for a in ("--external", n)]
        return _run(out, run_id, base, "--connect", ep, *ext)
    finally:
        _stop(*nodes, r)


def namespaces(out: Path, run_id: str, base: list[str]) -> float:
    from tests.integration.netns import MAIN, PLANT, ROUTER, ROUTER_ADDR, Topology

    t = Topology()
    try:
        r = _router("tcp/0.0.0.0:7447", prefix=t.cmd(ROUTER, []))
        plant = _cli("node", "plant", "--run", run_id, "--connect",
                     f"tcp/{ROUTER_ADDR[PLANT]}:7447", prefix=t.cmd(PLANT, []),
                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            return _run(out, run_id, base, "--connect", f"tcp/{ROUTER_ADDR[MAIN]}:7447",
                        "--external", "plant", prefix=t.cmd(MAIN, []))
        finally:
            _stop(plant, r)
    finally:
        t.close()


TRANSPORTS: dict[str, tuple[str, Callable[[Path, str, list[str]], float]]] = {
    "loopback": ("loopback peers (embedded default)", loopback_peers),
    "router-peers": ("`suscosim router` on loopback, nodes peers", router_peers),
    "router-clients": ("`suscosim router` on loopback, all nodes clients", router_clients),
    "netns": ("router / plant / rest in 3 network namespaces", namespaces),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=2.0, help="simulated time [s]")
    ap.add_argument("--h", type=float, default=0.001, help="communication step [s]")
    ap.add_argument("--repeat", type=int, default=3, help="runs per transport")
    ap.add_argument("--only", action="append", choices=sorted(TRANSPORTS),
                    help="measure only these transports (repeatable)")
    ap.add_argument("--out", help="run folders (default: a temporary folder)")
    args = ap.parse_args()
    from tests.integration.netns import unavailable

    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="bench-transport-"))
    base = ["--set", f"run.t_end={args.t_end}", "--set", f"run.h={args.h}"]
    n_steps = round(args.t_end / args.h)
    rows = []
    for key in args.only or list(TRANSPORTS):
        label, fn = TRANSPORTS[key]
        if key == "netns" and (reason := unavailable()):
            rows.append(f"| {label} | skipped: {reason} | |")
            continue
        rates = [fn(out / f"{key}-{i}", f"bt-{key}-{os.getpid()}-{i}", base)
                 for i in range(args.repeat)]
        rows.append(f"| {label} | {statistics.median(rates):.0f} | {max(rates):.0f} |")
        print(f"{key}: {', '.join(f'{r:.0f}' for r in rates)}", file=sys.stderr, flush=True)
    print(f"Chapter 3 step, h = {args.h * 1000:g} ms, {n_steps} coupled steps, "
          f"{args.repeat} runs each; {os.cpu_count()} CPUs, {platform.machine()}, "
          f"Python {platform.python_version()}\n")
    print("| transport | coupled steps/s (median) | best |")
    print("|---|---:|---:|")
    for row in rows:
        print(row)


if __name__ == "__main__":
    main()
