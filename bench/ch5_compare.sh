#!/usr/bin/env bash
# Chapter 5 comparison (thesis Table 5.3): passive, TSS1, TSS2, TSS3 on the lumped quarter car
# on several seeds of the same road; body RMS as the thesis computes it (0-20 Hz of the 500 Hz
# periodogram; suscosim ride) and % change against passive on the same seed (Eq 5.13),
# summarised as mean +- sample standard deviation over the seeds.
#
#   bash bench/ch5_compare.sh [SWEEP_FILE] [OUT_DIR]
#       default SWEEP_FILE: scenarios/thesis/ch5_mira_lumped.toml (MIRA substitute, 5 seeds)
#       default OUT_DIR:    sweeps/<sweep name>
#   bash bench/ch5_compare.sh --summarise OUT_DIR      (only the table, of a finished sweep)
#
# Runs the sweep (resumable: finished points are kept), then groups its points by every grid
# axis except road.seed; the law is the base scenario (scenarios/ch5_qvm_<law>_random.toml) or
# a "strategy" axis. Results: docs/ch5_control_comparison.md, docs/REPRODUCTION.md (Ch. 5).
set -euo pipefail
cd "$(dirname "$0")/.."
if [[ "${1:-}" == "--summarise" ]]; then
  out="$2"
else
  sweep="${1:-scenarios/thesis/ch5_mira_lumped.toml}"
  out="${2:-sweeps/$(basename "$sweep" .toml)}"
  python -m orchestrator sweep "$sweep" --out "$out" >&2
fi
python -m orchestrator ride "$out"/runs/* --json > "$out/ride.json"
python - "$out" <<'PY'
import json
import re
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

out = Path(sys.argv[1])
points = json.loads((out / "sweep.json").read_text())["points"]
ride = {Path(r["path"]).name: r["metrics"] for r in json.loads((out / "ride.json").read_text())["runs"]}
LAWS = ("passive", "tss1", "tss2", "tss3", "pnr")
KEYS = [("a_b_rms", "body RMS 0-20 Hz [m/s2]"), ("a_b_rms_0_16", "body RMS 0-16 Hz [m/s2]"),
        ("a_b_rms_full", "body RMS full band [m/s2]"), ("a_b_wk_rms", "body Wk RMS [m/s2]"),
        ("jerk_b_rms", "body jerk RMS [m/s3]"), ("a_w_rms", "wheel RMS 0-20 Hz [m/s2]"),
        ("sws", "working space [mm]"), ("dtl_rms", "dynamic tyre load RMS [N]"),
        ("alpha_pitch_rms", "body pitch acc. RMS 0-20 Hz [rad/s2]"),
        ("alpha_pitch_rms_0_16", "body pitch acc. RMS 0-16 Hz [rad/s2]"),
        ("alpha_roll_rms", "body roll acc. RMS 0-20 Hz [rad/s2]"),
        ("alpha_roll_rms_0_16", "body roll acc. RMS 0-16 Hz [rad/s2]")]
KEYS += [(f"a_arm_{loc}_{ax}_rms", f"arm {name} {ax} RMS 0-20 Hz [m/s2]")
         for loc, name in (("loc1", "Loc1"), ("cg", "CG"), ("loc2", "Loc2")) for ax in "xyz"]


def law_of(params):
    if "strategy" in params:
        return str(params["strategy"])
    m = re.search(r"ch5_\w*?(passive|tss1|tss2|tss3)", str(params.get("base", "")))
    return m.group(1) if m else str(params.get("base"))


table = defaultdict(lambda: defaultdict(dict))  # group -> law -> seed -> metrics
for p in points:
    run = Path(p["run_dir"]).name
    if run not in ride:
        continue
    params = dict(p["params"])
    seed = params.pop("road.seed", 0)
    law = law_of(params)
    params.pop("base", None), params.pop("strategy", None)
    group = ", ".join(f"{k}={v}" for k, v in params.items()) or "all"
    table[group][law][seed] = ride[run]

for group, laws in table.items():
    print(f"\n## {out.name}: {group}\n")
    base = laws.get("passive", {})
    seeds = sorted(base)
    print(f"seeds: {seeds} (mean +- sample std over the seeds; % = (passive - law) / passive"
          " x 100 on the same seed, positive = reduction)\n")
    order = [law for law in LAWS if law in laws] + [law for law in laws if law not in LAWS]
    print("| metric | " + " | ".join(order) + " |")
    print("|---|" + "---|" * len(order))
    first = next(iter(base.values())) if base else {}
    rows = []
    for key, label in KEYS:  # a full vehicle has the keys per corner: a_b[0]_rms ... a_b[3]_rms
        if key in first:
            rows.append((key, label))
            continue
        parts = key.split("_")
        n = 2 if parts[0] in ("a", "jerk") else 1
        for i, corner in enumerate(("FL", "FR", "RL", "RR")):
            k = "_".join(parts[:n]) + f"[{i}]" + "".join("_" + q for q in parts[n:])
            if k in first:
                rows.append((k, f"{label} {corner}"))
    for key, label in rows:
        cells = []
        for law in order:
            vals = np.array([laws[law][s][key] for s in seeds if s in laws[law]])
            if vals.size == 0:
                cells.append("-")
                continue
            cell = f"{vals.mean():.4g} ± {vals.std(ddof=1) if vals.size > 1 else 0:.2g}"
            if law != "passive" and all(base[s][key] for s in seeds):  # no % of a zero
                pct = np.array([(base[s][key] - laws[law][s][key]) / base[s][key] * 100
                                for s in seeds if s in laws[law]])
                cell += (f" ({pct.mean():+.1f} ± {pct.std(ddof=1) if pct.size > 1 else 0:.1f} %,"
                         f" {pct.min():+.1f}…{pct.max():+.1f})")
            cells.append(cell)
        print(f"| {label} | " + " | ".join(cells) + " |")
PY
