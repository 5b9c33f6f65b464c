"""What the co-simulation costs over the same work in one process (issue #41): per workload,
the coupled steps/s of the distributed run (a process per node over Zenoh), the steps/s of
the one-process engine (``--inprocess``: the same node models, one thread, no bus,
orchestrator/inprocess.py) and their ratio (distributed / in-process), the bare Zenoh round
trip and the load average, all in one run of this script, so that the ratios compare runs on
the same machine under the same load.

    python bench/bench_overhead.py [--json] [--repeats 1] [--rows lumped,corner,...]

Workloads (bench/workloads.py's): ``lumped`` the Ch 3 quarter car (h 1 ms), ``corner`` the Ch
6 realistic corner (h 0.5 ms) without live fatigue, ``corner_fatigue`` with it, ``full`` the
7-DOF vehicle (Ch 4, h 2 ms). Each run is a few seconds; the distributed and in-process runs
alternate, and each rate is the median of ``--repeats``. steps/s is summary.json's: from the
start to the last coupled step (the distributed run's sinks go on in parallel; the engine's
sinks are in its one thread). The round trip is bench/bench_zenoh_pingpong.py's (callback
subscriber, low-latency, express). ``--json`` prints one JSON object on its last line:
``{"lumped": {"coupled_steps_s", "inprocess_steps_s", "ratio", "inprocess_chain_steps_s",
"ratio_to_chain", "inprocess_cpu_steps_s"}, ..., "zenoh_rtt_us", "load"}``. The chain's rate
is the engine's with the time its sinks (recorder, live fatigue) took removed (summary.json
``inprocess``): the distributed run's sinks work on other cores. On a shared machine
wall-clock rates favour the distributed run (the scheduler gives each of its 5 processes a
share, the engine's one process one share): the in-process steps per second of CPU time is
the engine's work alone. Timing is measured here, never asserted in tests.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

T_END = {"lumped": 3.0, "corner": 1.0, "corner_fatigue": 1.0, "full": 2.0}
"""Simulated time per workload [s]: 1.5-3 s of wall time each on this machine."""


def load_average() -> float:
    return float(Path("/proc/loadavg").read_text().split()[0])


def steps_per_s(scenario: str, fatigue: bool | None, t_end: float,
                inprocess: bool) -> tuple[float, float, float]:
    """summary.json's steps/s of one run, and (in-process) the chain's alone (its sinks'
    time taken out: what the distributed run does on other cores) and the steps per second
    of the engine's CPU time (the work, whatever else the machine runs)."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "orchestrator", "run", str(ROOT / scenario), "--out", tmp,
               "--quiet", "--set", f"run.t_end={t_end}",
               *(["--inprocess"] if inprocess else ["--mode", "distributed"])]
        if fatigue is not None:
            cmd += ["--set", f"fatigue.live={'true' if fatigue else 'false'}"]
        res = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True,
                             env=dict(os.environ, PYTHONPATH=str(ROOT)))
        if res.returncode != 0:
            raise SystemExit(f"{scenario} ({'in-process' if inprocess else 'distributed'}): "
                             f"exit {res.returncode}: {res.stderr[-400:]}")
        summary = json.loads((Path(tmp) / "summary.json").read_text())
        inp = summary.get("inprocess") or {}
        cpu = float(inp.get("step_cpu_s", 0.0))
        return (float(summary["steps_per_s"]), float(inp.get("chain_steps_per_s", 0.0)),
                summary["n_steps"] / cpu if cpu > 0 else 0.0)


def main(argv: list[str] | None = None) -> int:
    from bench.bench_zenoh_pingpong import one as pingpong
    from bench.workloads import WORKLOADS

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="one JSON object on the last line")
    ap.add_argument("--repeats", type=int, default=1, help="runs of each kind per workload")
    ap.add_argument("--rows", default="lumped,corner,corner_fatigue,full")
    args = ap.parse_args(argv)
    rows = [r for r in args.rows.split(",") if r]
    known = [w[0] for w in WORKLOADS]
    if args.repeats < 1 or any(r not in known for r in rows):
        print(f"--rows: of {', '.join(known)}; --repeats >= 1", file=sys.stderr)
        return 2
    loads = [load_average()]
    rtt = pingpong(2000, fifo=False, ll=True, express=True)["rtt_us"]
    print(f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {os.cpu_count()} CPUs, "
          f"load {loads[0]:.2f}; bare Zenoh round trip {rtt:.0f} us\n")
    print("| workload | distributed steps/s | in-process steps/s | ratio | in-process chain "
          "steps/s (sinks out) | ratio to the chain | in-process steps per CPU s | load |")
    print("|---|---|---|---|---|---|---|---|")
    out: dict[str, object] = {}
    for key, label, scenario, fatigue in WORKLOADS:
        if key not in rows:
            continue
        dist, inproc, chain, cpu = [], [], [], []
        for _ in range(args.repeats):
            dist.append(steps_per_s(scenario, fatigue, T_END[key], inprocess=False)[0])
            i_all, i_chain, i_cpu = steps_per_s(scenario, fatigue, T_END[key], inprocess=True)
            inproc.append(i_all)
            chain.append(i_chain)
            cpu.append(i_cpu)
        d, i, c = statistics.median(dist), statistics.median(inproc), statistics.median(chain)
        u = statistics.median(cpu)
        loads.append(load_average())
        out[key] = {"coupled_steps_s": round(d, 1), "inprocess_steps_s": round(i, 1),
                    "ratio": round(d / i, 3), "inprocess_chain_steps_s": round(c, 1),
                    "ratio_to_chain": round(d / c, 3) if c > 0 else None,
                    "inprocess_cpu_steps_s": round(u, 1)}
        print(f"| {label} | {d:.0f} | {i:.0f} | {d / i:.2f} | {c:.0f} | "
              f"{d / c if c > 0 else float('nan'):.2f} | {u:.0f} | {loads[-1]:.2f} |",
              flush=True)
    out["zenoh_rtt_us"] = round(rtt, 1)
    out["load"] = [round(x, 2) for x in loads]
    if args.json:
        print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
