"""Coupled steps per second of the distributed Chapter 3 run, and CPU per coupled step.

Four node processes (plant, tyre/road, controller, recorder) over Zenoh on loopback,
h = 1 ms, both exchange orders. steps/s is summary.json's: from ``start`` to the last coupled
node's ``done``; "incl. export" also counts the recorder's table export after the last step.
Wall-clock throughput depends on what else the 2 cores are doing; CPU per step (all
processes, user + system, startup subtracted) is the steadier number.

    python bench/bench_throughput.py [--repeats 3] [--t-end 8] [--pin auto|on|off]
                                     [--lowlatency] [--exchange sequential|parallel]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "ch3_step_quarter_car.toml"


def one_run(t_end: float, exchange: str, extra: list[str]) -> tuple[float, float, float]:
    """(steps/s, steps/s incl. the export, CPU seconds of the whole run incl. every node)."""
    with tempfile.TemporaryDirectory() as tmp:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run([sys.executable, "-m", "orchestrator", "run", str(SCENARIO), "--out",
                        tmp, "--quiet", "--set", f"run.t_end={t_end}",
                        "--set", f'run.exchange="{exchange}"', *extra],
                       cwd=ROOT, check=True, capture_output=True,
                       env=dict(os.environ, PYTHONPATH=str(ROOT)))
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        summary = json.loads((Path(tmp) / "summary.json").read_text())
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    with_export = summary["n_steps"] / summary["run_wall_s"]
    return float(summary["steps_per_s"]), with_export, cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--t-end", type=float, default=8.0)
    ap.add_argument("--lowlatency", action=argparse.BooleanOptionalAction, default=None,
                    help="Zenoh's low-latency transport (suscosim run --lowlatency; default: "
                         "the run's default, universal since it could wedge a start)")
    ap.add_argument("--pin", choices=["auto", "on", "off"], default="auto",
                    help="CPU placement of the node processes (suscosim run --pin)")
    ap.add_argument("--exchange", choices=["sequential", "parallel"], action="append",
                    help="exchange order(s) to measure (default both)")
    args = ap.parse_args()
    extra = ([] if args.lowlatency is None else
             ["--lowlatency" if args.lowlatency else "--no-lowlatency"]) + ["--pin", args.pin]
    _, _, cpu0 = one_run(0.001, "sequential", extra)  # startup cost: imports, sessions, barrier
    n = round(args.t_end / 0.001)
    load = os.getloadavg()[0]
    print(f"load average at start: {load:.1f}; startup CPU {cpu0:.2f} s")
    print("| exchange | steps/s (median) | steps/s (all runs) | incl. export (median) "
          "| CPU per step (ms) |")
    print("|---|---|---|---|---|")
    for exchange in args.exchange or ("sequential", "parallel"):
        rates, exported, cpus = [], [], []
        for _ in range(args.repeats):
            r, e, c = one_run(args.t_end, exchange, extra)
            rates.append(r)
            exported.append(e)
            cpus.append((c - cpu0) / n * 1e3)
        print(f"| {exchange} | {statistics.median(rates):.0f} | "
              f"{', '.join(f'{r:.0f}' for r in rates)} | {statistics.median(exported):.0f} | "
              f"{statistics.median(cpus):.2f} |", flush=True)
    print(f"load average at end: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
