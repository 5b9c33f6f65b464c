"""One CAD variant of the built-in pivot-tube arm through the part card's FE (#26 item 2).

    python bench/arm_variant.py --size 0.03 --set section.rib_depth_root=0.047 [--modes 1]

Builds ``cad_arm`` with the part file's CAD parameters overridden by ``--set table.key=value``
(a JSON value), meshes it at ``--size`` (fillet size scaled as the card does), solves the
unit cases (and ``--modes`` modes) and prints mass, first mode, the static hot spot, 3 g /
yield and where the ten hot spots sit, with the wall time of each step. The part file
(joints, zones, material) is ``nodes/fatigue/parts/data/lower_arm.toml``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from nodes.fatigue.parts import cad_arm  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=float, default=0.03)
    ap.add_argument("--modes", type=int, default=1)
    ap.add_argument("--set", action="append", default=[], metavar="TABLE.KEY=JSON")
    args = ap.parse_args()
    params = cad_arm.load_params()
    for s in args.set:
        key, val = s.split("=", 1)
        table, k = key.split(".")
        params[table][k] = json.loads(val)
    cad_arm.load_params = lambda path=None: params  # part_model reads the CAD parameters here

    from nodes.fatigue.parts.build import part_model, solve_part
    from nodes.fatigue.parts.card import _hot_spots
    from nodes.fatigue.parts.schema import load_part
    from orchestrator.studies.arm_card import static_arm_loads

    part = load_part(cad_arm.DATA / "lower_arm.toml")
    t0 = time.perf_counter()
    pm = part_model(part, args.size)
    t1 = time.perf_counter()
    inf, ex = solve_part(pm, args.modes)
    t2 = time.perf_counter()
    loads = static_arm_loads()
    names = list(inf.case_names)
    import numpy as np

    f = np.array([loads.get(n, 0.0) for n in names])
    hot, vm = _hot_spots(pm, ex["coef"], f, ex["labels"])
    m = inf.meta
    out = {"set": args.set, "size_m": args.size, "n_nodes": m["n_nodes"],
           "mass_kg": m["mass_kg"], "solid_mass_kg": m["solid_mass_kg"],
           "modes_hz": m["natural_frequencies_hz"],
           "static_hotspot_mpa": hot[0]["von_mises_mpa"],
           "ratio_3g_to_yield": 3e6 * hot[0]["von_mises_mpa"] / part.material.Sy,
           "hot_spots_mm_mpa": [[round(1e3 * v, 1) for v in h["xyz_m"]]
                                + [round(h["von_mises_mpa"], 1)] for h in hot],
           "nearest_sharp_edge_mm": min(h["distance_to_sharp_edge_m"] for h in hot) * 1e3,
           "zone_peak_mpa": float(vm[~pm.assessed].max()) / 1e6,
           "time_mesh_s": round(t1 - t0, 1), "time_solve_s": round(t2 - t1, 1)}
    print(json.dumps(out))


if __name__ == "__main__":
    main()
