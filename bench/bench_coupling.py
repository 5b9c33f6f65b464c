"""Effect of the coupling mode (hold, linear, jacobian) and exchange order on accuracy.

    python bench/bench_coupling.py [--steps 0.001,0.002,0.005]

Monolithic runs (same node code and numbers as distributed, without the transport) of the
Chapter 3 step; worst peak error (Eq. 3.5) against the reference, per signal.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from cosim import scenario as sc
from cosim.table import read_table
from orchestrator.accuracy import peak_errors, worst
from orchestrator.reference import reference_solution
from orchestrator.runner import resolve, run_scenario

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "ch3_step_quarter_car.toml"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", default="0.001,0.002,0.005")
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="suscosim-coupling-"))
    ref = reference_solution(resolve(sc.load(SCENARIO), tmp / "p"),
                             np.arange(0, 4.0 + 1e-9, 2e-5))
    print(f"{'exchange':>10} {'coupling':>9} {'h [s]':>6}  worst |peak error| [%] "
          "(z_b max, z_w max, a_w max/min, F_t max/min)")
    for exchange in ("sequential", "parallel"):
        for coupling in ("hold", "linear", "jacobian"):
            for h in (float(x) for x in args.steps.split(",")):
                d = tmp / f"{exchange}-{coupling}-{h}"
                s = resolve(sc.load(SCENARIO, [f"run.h={h}", f'run.coupling="{coupling}"',
                                               f'run.exchange="{exchange}"',
                                               'run.mode="monolithic"']), d)
                run_scenario(s, quiet=True)
                e = peak_errors(read_table(d / "table.parquet"), ref, t_from=0.4)
                flat = [e[k][m] for k in e for m in e[k]]
                print(f"{exchange:>10} {coupling:>9} {h:>6} {worst(e):8.3f}   "
                      + " ".join(f"{v:+.2f}" for v in flat))


if __name__ == "__main__":
    main()
