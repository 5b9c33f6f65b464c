"""Chapter 6 comparison, read more closely: a finished ``ch6_fatigue``-style sweep folder in,
the tables of docs/REPRODUCTION.md out.

    python bench/ch6_sensitivity.py sweeps/ch6_fatigue [--methods]

For every road of the sweep (points ``<name>-<road>-<strategy>``, strategies passive, tss1,
tss2, tss3) it prints

* the minimum life of the arm (any node, the thesis's headline) per strategy and its change
  against passive;
* the thesis's convention: the mean over passive's 4 most damaged nodes of the per-node life
  reduction (Tables 6.3-6.6 give 4 resp. 3 fixed nodes; "48/68/96 %" is that mean);
* the life at the notch: the most damaged node (under passive) within 30 mm of the outboard
  corner of the lightening hole (``HOLE_CORNERS[2]``, the analogue of the thesis's node 217,
  "near the notch, bottom section").

With ``--methods`` it also recomputes the minimum lives from the run tables under other
fatigue settings (equivalent stress, mean-stress correction, strain-life), without touching
the run folders. Reads only; writes nothing.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

STRATEGIES = ("passive", "tss1", "tss2", "tss3")
METHODS = (("abs_max_principal", "stress_life", "goodman"),
           ("abs_max_principal", "stress_life", "none"),
           ("signed_von_mises", "stress_life", "goodman"),
           ("abs_max_principal", "strain_life", "swt"))


def _per_node(run_dir: Path) -> dict[str, np.ndarray]:
    with open(run_dir / "fatigue" / "damage_per_node.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    return {"ids": np.array([int(r["node_id"]) for r in rows]),
            "damage": np.array([float(r["damage_per_pass"]) for r in rows]),
            "life_km": np.array([float(r["life_km"]) for r in rows]),
            "xyz": np.array([[float(r[k]) for k in ("x_m", "y_m", "z_m")] for r in rows])}


def _pct(value: float, base: float) -> str:
    return f"{100.0 * (value / base - 1.0):+.0f} %"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sweep_dir", type=Path)
    ap.add_argument("--methods", action="store_true", help="also other fatigue settings")
    args = ap.parse_args(argv)
    from cosim.lower_arm import HOLE_CORNERS

    doc = json.loads((args.sweep_dir / "sweep.json").read_text())
    notch_xy = HOLE_CORNERS[2]
    roads = list(dict.fromkeys(p["params"]["road"] for p in doc["points"]
                               if "road" in p["params"]))
    by = {(p["params"].get("road"), p["params"]["strategy"]): args.sweep_dir / p["run_dir"]
          for p in doc["points"]}
    for road in roads:
        runs = {s: by[(road, s)] for s in STRATEGIES}
        nodes = {s: _per_node(d) for s, d in runs.items()}
        summ = {s: json.loads((d / "fatigue" / "summary.json").read_text())
                for s, d in runs.items()}
        p = nodes["passive"]
        top4 = p["ids"][np.argsort(p["damage"])[::-1][:4]]
        near = np.hypot(p["xyz"][:, 0] - notch_xy[0], p["xyz"][:, 1] - notch_xy[1]) < 0.03
        i_notch = int(np.argmax(np.where(near, p["damage"], -1.0)))
        xyz = ", ".join(f"{v * 1e3:.0f}" for v in p["xyz"][i_notch])
        print(f"\n{road}: track {summ['passive']['track_length_m']:g} m; passive's 4 most "
              f"damaged nodes {', '.join(map(str, top4))}; notch node "
              f"{p['ids'][i_notch]} at ({xyz}) mm")
        print(f"  {'strategy':<8} {'min life km':>12} {'repeats':>11} {'node':>5} "
              f"{'change':>8} {'top-4 mean reduction':>21} {'notch life km':>14} {'change':>8}")
        base_min = summ["passive"]["min_life_km"]
        for s in STRATEGIES:
            q, sm = nodes[s], summ[s]
            red = []
            for n in top4:
                i = int(np.where(q["ids"] == n)[0][0])
                j = int(np.where(p["ids"] == n)[0][0])
                red.append(100.0 * (1.0 - q["life_km"][i] / p["life_km"][j]))
            notch = q["life_km"][int(np.where(q["ids"] == p["ids"][i_notch])[0][0])]
            print(f"  {s:<8} {sm['min_life_km']:>12.4g} {sm['min_life_repeats']:>11.4g} "
                  f"{sm['critical_node_id']:>5} {_pct(sm['min_life_km'], base_min):>8} "
                  f"{np.mean(red):>+20.1f}% {notch:>14.4g} "
                  f"{_pct(notch, p['life_km'][i_notch]):>8}")
        if args.methods:
            from nodes.fatigue.config import FatigueConfig
            from nodes.fatigue.run_dir import read_table, track_length
            from nodes.fatigue.worker import analyse

            print("  minimum life [km] (critical node) under other fatigue settings:")
            for eq, method, mean in METHODS:
                cells = {}
                for s, d in runs.items():
                    t, loads = read_table(d)
                    scen = json.loads((d / "scenario.json").read_text())
                    cfg = FatigueConfig.from_dict({"equivalent": eq, "method": method,
                                                   "mean_stress": mean})
                    r = analyse(t, loads, cfg, track_length(scen, t))
                    cells[s] = (r.life_km, r.critical_node_id)
                b = cells["passive"][0]
                print(f"    {eq}/{method}/{mean}: " + "; ".join(
                    f"{s} {v:.3g} ({n}) {_pct(v, b) if s != 'passive' else ''}".rstrip()
                    for s, (v, n) in cells.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
