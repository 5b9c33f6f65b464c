"""Does the coupling's energy residual predict the co-simulation's error? (issue #29)

    python bench/bench_coupling_residual.py [--steps 0.00025,0.0005,0.001,0.002,0.004]
                                            [--csv OUT.csv]

The Chapter 3 quarter car over its 20 mm step, monolithic (the same node code and numbers as
distributed, without the transport), for every exchange order and coupling mode and each
communication step h: the worst peak error against the reference solution (Eq. 3.5, %, the
"true" error) beside the energy residual of :mod:`cosim.coupling_energy` (relative, %, per
bond and in total), which needs no reference. Prints a markdown table (and a CSV with --csv).
"""

from __future__ import annotations

import argparse
import csv
import tempfile
from pathlib import Path

import numpy as np

from cosim import coupling_energy as ce
from cosim import scenario as sc
from cosim.table import read_table
from orchestrator.accuracy import peak_errors, worst
from orchestrator.reference import reference_solution
from orchestrator.runner import resolve, run_scenario

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "ch3_step_quarter_car.toml"


def study(steps: list[float], tmp: Path) -> list[dict[str, float | str]]:
    """One row per (exchange, coupling, h): true worst peak error and the residuals [%]."""
    ref = reference_solution(resolve(sc.load(SCENARIO), tmp / "p"),
                             np.arange(0, 4.0 + 1e-9, 2e-5))
    rows: list[dict[str, float | str]] = []
    for exchange in ("sequential", "parallel"):
        for coupling in ("hold", "linear", "jacobian"):
            for h in steps:
                d = tmp / f"{exchange}-{coupling}-{h}"
                s = resolve(sc.load(SCENARIO, [f"run.h={h}", f'run.coupling="{coupling}"',
                                               f'run.exchange="{exchange}"',
                                               'run.mode="monolithic"']), d)
                run_scenario(s, quiet=True)
                table = read_table(d / "table.parquet")
                res = ce.summary(ce.coupling_residual(table, h, coupling, exchange))
                rows.append({"exchange": exchange, "coupling": coupling, "h": h,
                             "true_peak_error_pct": worst(peak_errors(table, ref, t_from=0.4)),
                             **{f"residual_{b}_pct": 100 * v for b, v in res.items()}})
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", default="0.00025,0.0005,0.001,0.002,0.004")
    ap.add_argument("--csv", help="also write the rows to this CSV file")
    args = ap.parse_args()
    rows = study([float(x) for x in args.steps.split(",")],
                 Path(tempfile.mkdtemp(prefix="suscosim-residual-")))
    print("| exchange | coupling | h [ms] | true worst peak error [%] | residual damper [%] "
          "| residual tyre [%] | residual total [%] | total / true |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        true, tot = float(r["true_peak_error_pct"]), float(r["residual_total_pct"])
        ratio = f"{tot / true:.2f}" if true > 0 else "-"
        print(f"| {r['exchange']} | {r['coupling']} | {1e3 * float(r['h']):g} | {true:.3f} "
              f"| {float(r.get('residual_damper_pct', 0)):.3g} "
              f"| {float(r.get('residual_tyre_pct', 0)):.3g} | {tot:.3g} | {ratio} |")
    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)


if __name__ == "__main__":
    main()
