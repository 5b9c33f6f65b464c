"""The adaptive communication step (``run.h = "auto"``, issue #29 item 3) against fixed steps,
on the lumped quarter car, where the reference mode gives the true solution.

For each road (the Ch 3 step, the Ch 4 bump + pothole) and the coupling ``hold`` (the
thesis's; its error is the coupling's, which the energy residual measures): runs at fixed
h = 0.25 ... 4 ms and with ``run.h = "auto"`` at several tolerances, monolithic; per run the
number of communication steps and the worst peak error of Table 3.3's signals against the
reference (Eq. 3.5). Prints a table (Markdown) and writes it as JSON beside ``--out``.

    python bench/adaptive_step.py --out /tmp/adaptive            # ~2 min on 2 cores
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cosim.table import read_table  # noqa: E402
from orchestrator.accuracy import peak_errors, worst  # noqa: E402

BUMP_POTHOLE = ('road={type="events", speed_kmh=34.0, length_m=15.0, events=['
                '{type="bump", height=0.05, length=1.0, x_start=3.0}, '
                '{type="pothole", depth=0.04, length=0.6, x_start=10.0, shape="cosine"}]}')
ROADS = {"step": [], "bump_pothole": ["--set", BUMP_POTHOLE, "--set", "run.t_end=0"]}
FIXED_MS = (0.25, 0.5, 1.0, 2.0, 4.0)
TOLS = (1e-2, 3e-3, 1e-3, 3e-4)


def run(out: Path, *sets: str) -> dict:
    if not (out / "summary.json").is_file():
        r = subprocess.run([sys.executable, "-m", "orchestrator", "run",
                            str(ROOT / "scenarios" / "ch3_step_quarter_car.toml"), "--out",
                            str(out), "--quiet", *sets], capture_output=True, text=True,
                           cwd=ROOT)
        if r.returncode != 0:
            raise SystemExit(f"{out}: {r.stderr[-2000:]}")
    return json.loads((out / "summary.json").read_text())


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("/tmp/adaptive_step"))
    ap.add_argument("--coupling", default="hold")
    args = ap.parse_args(argv)
    rows = []
    for road, road_sets in ROADS.items():
        base = [*road_sets, "--set", f'run.coupling="{args.coupling}"']
        ref_dir = args.out / road / "reference"
        run(ref_dir, *base, "--mode", "reference", "--set", "run.h=0.00025")
        ref = read_table(ref_dir / "table.parquet")
        cases = [(f"fixed {ms:g} ms", ["--set", f"run.h={ms / 1000:g}"]) for ms in FIXED_MS]
        cases += [(f"auto tol {tol:g}", ["--set", 'run.h="auto"', "--set", f"run.h_tol={tol:g}"])
                  for tol in TOLS]
        for label, sets in cases:
            d = args.out / road / label.replace(" ", "_")
            s = run(d, *base, "--mode", "monolithic", *sets)
            err = worst(peak_errors(read_table(d / "table.parquet"), ref, t_from=0.0))
            a = s.get("adaptive_step", {})
            rows.append({"road": road, "run": label, "steps": s["n_steps"],
                         "worst_peak_error_pct": err,
                         "residual_pct": 100 * s.get("coupling_energy_residual", {})
                         .get("total", float("nan")),
                         "h_smallest_ms": 1e3 * a["h_smallest"] if a else None,
                         "h_largest_ms": 1e3 * a["h_largest"] if a else None})
    print("| road | run | steps | worst peak error | residual | h range [ms] |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        hr = (f"{r['h_smallest_ms']:.3g}-{r['h_largest_ms']:.3g}" if r["h_smallest_ms"]
              else "")
        print(f"| {r['road']} | {r['run']} | {r['steps']} | {r['worst_peak_error_pct']:.3f} % "
              f"| {r['residual_pct']:.3g} % | {hr} |")
    args.out.mkdir(parents=True, exist_ok=True)
    tmp = args.out / "adaptive_step.json.tmp"
    tmp.write_text(json.dumps(rows, indent=1))
    tmp.replace(args.out / "adaptive_step.json")
    return 0


if __name__ == "__main__":
    sys.exit(main())
