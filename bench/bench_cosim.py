"""Cost and accuracy of the co-simulation, as Tables 3.2 and 3.3 of the thesis.

    python bench/bench_cosim.py [--steps 0.001,0.002,0.003,0.004,0.005] [--repeat 1]
                                [--coupling jacobian] [--out bench/out]

For each communication step h: wall time of the reference (solve_ivp), monolithic (one
process, in-memory bus) and distributed (4 node processes over Zenoh on loopback) runs of the
Chapter 3 step, coupled steps per second, and the peak errors (Eq. 3.5) of the distributed run
against the reference (true peaks on a 20 us grid). Also the coupling modes at 1 and 2 ms.
Timing is measured here, never asserted in tests.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from cosim import scenario as sc
from cosim.table import read_table
from orchestrator.accuracy import peak_errors, worst
from orchestrator.reference import reference_solution
from orchestrator.runner import resolve, run_scenario

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "ch3_step_quarter_car.toml"


def one(out: Path, overrides: list[str]) -> tuple[dict, dict]:
    s = resolve(sc.load(SCENARIO, overrides), out)
    t0 = time.perf_counter()
    summary = run_scenario(s, quiet=True)
    summary["bench_wall_s"] = time.perf_counter() - t0
    return s, summary


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", default="0.001,0.002,0.003,0.004,0.005")
    ap.add_argument("--repeat", type=int, default=1, help="distributed runs per step (best kept)")
    ap.add_argument("--coupling", default="jacobian")
    ap.add_argument("--out", default=str(ROOT / "bench" / "out"))
    args = ap.parse_args()
    out = Path(args.out)
    steps = [float(x) for x in args.steps.split(",")]
    scenario = resolve(sc.load(SCENARIO), out / "probe")
    ref = reference_solution(scenario, np.arange(0, 4.0 + 1e-9, 2e-5))
    rows = []
    for h in steps:
        base = [f"run.h={h}", f'run.coupling="{args.coupling}"']
        _, r = one(out / f"ref-{h}", base + ['run.mode="reference"'])
        _, m = one(out / f"mono-{h}", base + ['run.mode="monolithic"'])
        best = None
        for i in range(args.repeat):
            _, d = one(out / f"dist-{h}-{i}", base)
            if best is None or d["steps_per_s"] > best["steps_per_s"]:
                best, best_dir = d, out / f"dist-{h}-{i}"
        err = peak_errors(read_table(best_dir / "table.parquet"), ref, t_from=0.4)
        rows.append({"h": h, "reference_s": r["bench_wall_s"], "monolithic_s": m["bench_wall_s"],
                     "distributed_s": best["bench_wall_s"],
                     "distributed_steps_per_s": best["steps_per_s"],
                     "monolithic_steps_per_s": m["steps_per_s"],
                     "worst_peak_error_pct": worst(err), "errors": err})
    print("\nTable 3.2 (ours): wall time [s] of the 4 s Chapter 3 step run")
    print(f"{'h [s]':>7} {'reference':>10} {'monolithic':>11} {'distributed':>12} "
          f"{'dist steps/s':>13} {'mono steps/s':>13}")
    for r in rows:
        print(f"{r['h']:>7} {r['reference_s']:>10.2f} {r['monolithic_s']:>11.2f} "
              f"{r['distributed_s']:>12.2f} {r['distributed_steps_per_s']:>13.0f} "
              f"{r['monolithic_steps_per_s']:>13.0f}")
    print("\nTable 3.3 (ours): peak error of the distributed run against the reference [%]")
    labels = list(rows[0]["errors"])
    print(f"{'h [s]':>7} " + " ".join(f"{lab[:18] + ' ' + k:>24}" for lab in labels
                                      for k in rows[0]["errors"][lab]))
    for r in rows:
        print(f"{r['h']:>7} " + " ".join(f"{r['errors'][lab][k]:>24.3f}" for lab in labels
                                        for k in r["errors"][lab]))
    (out / "bench_cosim.json").write_text(json.dumps(rows, indent=2, default=float))


if __name__ == "__main__":
    main()
