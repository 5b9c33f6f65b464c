"""Which fillets OpenCASCADE can put on the pivot-tube forged arm, and in which order (#26 item 2).

    python bench/arm_fillet_order.py        # CAD only (no FE), about 1 min

The pivot-tube variant of docs/parts.md (690 Hz, 5.42 kg) misses 3 g <= 0.8 yield at an
unfilleted rib-eye junction; its sharp junction stress is a corner singularity that no mesh
converges. This script builds the unfilleted solid (``cad_arm.build(..., fillet=False)``),
splits its sharp re-entrant edges (features.py, material share > 0.6) into the **web roots**
(in the web's planes z = +-t/2) and the **junctions** (ribs meeting the eye tubes and the
ball-joint housing, the pivot tube's bore steps), and tries: (1) every edge in one pass,
(2) the junctions first at radius ``R_JUNCTION``, then greedily as many web-root edges as
OCC accepts at the section's fillet radius (5 mm). It prints the counts, and the edges left.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from nodes.fatigue.parts import cad_arm  # noqa: E402
from nodes.fatigue.parts.features import sharp_reentrant_edges  # noqa: E402

R_JUNCTION = 0.003
"""Junction fillet radius [m] (5 mm breaks on the pivot tube's 3 mm bore steps)."""


def variant(d0: float, d1: float, boss: float) -> dict[str, Any]:
    """The pivot-tube arm of docs/parts.md (ribs 6 mm, eyes OD 58, housing OD 58 x 32 mm,
    pivot-tube bore 50 mm) with root / tip rib depth d0 / d1 and bush boss plan radius."""
    p = cad_arm.load_params()
    p["bush_eye"].update(pivot_tube=True, pivot_tube_bore=0.025, outer_radius=0.029)
    p["section"].update(outer_rib_width=0.006, hole_rib_width=0.006, rib_depth_root=d0,
                        rib_depth_tip=d1)
    p["ball_joint"].update(outer_radius=0.029, depth=0.032)
    p["plan"]["bush_boss_radius"] = boss
    return p


def split(volume: int, web: float) -> tuple[list[int], list[int]]:
    """(web-root curves, other sharp re-entrant curves) of an OCC volume."""
    roots: list[int] = []
    other: list[int] = []
    for e in sharp_reentrant_edges(volume):
        z = e["points_m"][:, 2]
        (roots if np.all(np.abs(np.abs(z) - web / 2) < 1e-6) else other).append(e["curve"])
    return roots, other


def fillet(volume: int, curves: list[int], r: float) -> int | None:
    """The filleted volume's tag, or None where OCC cannot compute it."""
    import gmsh  # type: ignore[import-untyped]

    try:
        out = gmsh.model.occ.fillet([volume], curves, [r])
        gmsh.model.occ.synchronize()
    except Exception:  # OCC's "Could not compute fillet"
        return None
    return [e[1] for e in out if e[0] == 3][0]


def trial(name: str, p: dict[str, Any]) -> str:
    import gmsh  # type: ignore[import-untyped]

    t, r = float(p["section"]["web"]), float(p["section"]["fillet"])
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("a")
        v = cad_arm.build(p, fillet=False)["volume"][0]
        roots, other = split(v, t)
        one = fillet(v, roots + other, R_JUNCTION) is not None
        gmsh.model.remove()
        gmsh.model.add("b")
        v = cad_arm.build(p, fillet=False)["volume"][0]
        roots, other = split(v, t)
        vj = fillet(v, other, R_JUNCTION)
        if vj is None:
            return f"| {name} | {len(roots)} / {len(other)} | {one} | junctions fail | - |"
        roots2, other2 = split(vj, t)
        good: list[int] = []
        for c in roots2:  # greedy: keep every web-root edge OCC accepts with the others
            test = fillet(vj, good + [c], r)
            if test is not None:
                gmsh.model.occ.remove([(3, test)], recursive=True)
                gmsh.model.occ.synchronize()
                good.append(c)
        return (f"| {name} | {len(roots)} / {len(other)} | {one} | all {len(other)} ok "
                f"({len(other2)} left) | {len(good)} of {len(roots2)} |")
    finally:
        gmsh.finalize()


def main() -> int:
    print("| variant | web roots / junctions (unfilleted) | one pass ok | junctions first "
          "(3 mm) | web roots then (5 mm, greedy) |")
    print("|---|---|---|---|---|")
    for name, args in (("ribs 36/32 mm, boss 29 mm", (0.036, 0.032, 0.029)),
                       ("ribs 46/32 mm, boss 29 mm", (0.046, 0.032, 0.029)),
                       ("ribs 36/26 mm, boss 25 mm", (0.036, 0.026, 0.025))):
        print(trial(name, variant(*args)), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
