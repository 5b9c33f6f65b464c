"""Which CAD variants of the built-in pivot-tube arm OpenCASCADE can fillet (#26 item 2).

    python bench/arm_cad_grid.py '[{"section.rib_depth_root": 0.046}, {...}]'   # CAD only

Each variant overrides the part file's CAD parameters (``data/lower_arm_cad.toml``;
"table.key": value, metres) and is built by ``cad_arm.build`` (the one fillet pass before the
bores); prints OK with the forging's OCC mass (7850 kg/m^3) and the sharp re-entrant edges
left, or FAIL with OCC's message. A few seconds per variant.
"""

from __future__ import annotations

import copy
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from nodes.fatigue.parts import cad_arm  # noqa: E402
from nodes.fatigue.parts.features import sharp_reentrant_edges  # noqa: E402


def main() -> None:
    import gmsh  # type: ignore[import-untyped]

    base = cad_arm.load_params()
    gmsh.initialize(interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        for v in json.loads(sys.argv[1]):
            p = copy.deepcopy(base)
            for k, val in v.items():
                table, key = k.split(".")
                p[table][key] = val
            gmsh.model.add("variant")
            try:
                vol = cad_arm.build(p)["volume"][0]
                mass = gmsh.model.occ.getMass(3, vol) * 7850.0
                print(json.dumps(v), f"OK mass {mass:.3f} kg, sharp edges "
                      f"{len(sharp_reentrant_edges(vol))}", flush=True)
            except Exception as exc:  # OCC raises a bare Exception when a fillet fails
                print(json.dumps(v), "FAIL", str(exc)[:60], flush=True)
            gmsh.model.remove()
    finally:
        gmsh.finalize()


if __name__ == "__main__":
    main()
