"""Thesis Tables 5.6-5.11 layout of the full-vehicle pave sweep (ch5_pave_fvm.toml).

    bash bench/ch5_compare.sh scenarios/thesis/ch5_pave_fvm.toml   # runs it, writes ride.json
    python bench/ch5_pave_tables.py sweeps/ch5_pave_fvm

The metric rows are, per corner (FL, FR, RL, RR): body vertical RMS 0-20 Hz (Table 5.6) and 0-16 Hz
(Tables 5.7-5.10, z), and wheel vertical RMS 0-20 Hz (Table 5.11); and, for the body as a whole,
pitch and roll acceleration RMS 0-16 Hz (rad/s^2; the 7-DOF body has no x or y translation, so
these are what it has for Tables 5.7-5.10's x and y rows). Each row gives passive / TSS1 / PnR
at every speed: the mean over the seeds, and the mean of the per-seed % against passive
(thesis Eq 5.13, positive = reduction).
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

from cosim.channels import CORNERS

LAWS = ("passive", "tss1", "pnr")


def main(out: Path) -> None:
    points = json.loads((out / "sweep.json").read_text())["points"]
    ride = {Path(r["path"]).name: r["metrics"]
            for r in json.loads((out / "ride.json").read_text())["runs"]}
    data: dict = defaultdict(lambda: defaultdict(dict))  # (law, speed) -> seed -> metrics
    for pt in points:
        run = Path(pt["run_dir"]).name
        if run in ride:
            prm = pt["params"]
            data[(prm["strategy"], float(prm["road.speed_kmh"]))][prm["road.seed"]] = ride[run]
    speeds = sorted({s for _, s in data})
    rows = []
    for key, label in (("a_b[{i}]_rms", "body z 0-20 Hz [m/s2]"),
                       ("a_b[{i}]_rms_0_16", "body z 0-16 Hz [m/s2]"),
                       ("a_w[{i}]_rms", "wheel z 0-20 Hz [m/s2]")):
        rows += [(key.format(i=i), f"{c} {label}") for i, c in enumerate(CORNERS)]
    rows += [("alpha_pitch_rms_0_16", "pitch acc. 0-16 Hz [rad/s2]"),
             ("alpha_roll_rms_0_16", "roll acc. 0-16 Hz [rad/s2]")]
    print("| metric | law | " + " | ".join(f"{s:g} km/h" for s in speeds) + " |")
    print("|---|---|" + "---|" * len(speeds))
    for key, label in rows:
        for law in LAWS:
            cells = []
            for s in speeds:
                base, runs = data[("passive", s)], data[(law, s)]
                seeds = sorted(set(base) & set(runs))
                if not seeds or key not in runs[seeds[0]]:
                    cells.append("-")
                    continue
                v = np.mean([runs[k][key] for k in seeds])
                cell = f"{v:.4g}"
                if law != "passive":
                    pct = [(base[k][key] - runs[k][key]) / base[k][key] * 100 for k in seeds]
                    cell += f" ({np.mean(pct):+.1f} %)"
                cells.append(cell)
            print(f"| {label} | {law} | " + " | ".join(cells) + " |")
    n = {k: len(v) for k, v in data.items()}
    print(f"\nseeds per (law, speed): {sorted(set(n.values()))}")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
