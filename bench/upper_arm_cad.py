"""Make the upper wishbone's STEP file (nodes/fatigue/parts/data/upper_arm.step) with gmsh's
OpenCASCADE kernel, and optionally print its model card under the plant's static loads.

    python3 bench/upper_arm_cad.py                 # writes the STEP (CAD only, ~1 s)
    python3 bench/upper_arm_cad.py --card [--mesh-size 0.008] [--out STEP]

The part (docs/parts.md, "A second part: the upper wishbone"): a forged A-arm in the
upper-arm frame of ``plant/upper_arm`` (origin the upper bushes' midpoint, x along the pivot
axis forward, y toward the upper ball joint, z = x cross y), its centres the corner file's
upper hardpoints read through :func:`nodes.fatigue.parts.hardpoints.hardpoints` (one
definition): two bush eyes (tubes along x), a ball-joint boss (a ring about z), two legs of
a solid rectangular section from the eyes to the boss and a cross member between them;
filleted where the legs and the cross member meet the eyes, the boss and each other; the
bores cut after the fillets (cad_arm.py's lesson: an OCC fillet pass on a solid with its bores
already cut can turn it inside out).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from nodes.fatigue.parts.hardpoints import hardpoints  # noqa: E402

OUT = ROOT / "nodes" / "fatigue" / "parts" / "data" / "upper_arm.step"

EYE_OD, EYE_BORE, EYE_LEN = 0.042, 0.030, 0.036
"""Bush eyes [m]: tubes along x (the bush's outer sleeve is pressed into the bore)."""
BOSS_OD, BOSS_BORE, BOSS_H = 0.046, 0.032, 0.020
"""Ball-joint boss [m]: a ring about z (the ball-joint cartridge is pressed into the bore), as
deep as the legs: flush faces, so that every junction edge there is vertical (OCC fillets
those; a leg's top face meeting a deeper boss's wall was refused)."""
LEG_W, LEG_H = 0.012, 0.020
"""Legs [m]: width in plan, depth in z (a solid rectangular section)."""
CROSS_Y, CROSS_W, CROSS_H = 0.085, 0.010, 0.020
"""Cross member [m]: at this distance from the pivot axis, width along y, depth in z (the
legs' depth: flush, as the boss)."""
FILLET = 0.003
"""Fillet radius at every junction (sharp re-entrant edge) [m]."""
STEEL = 7850.0


def _bar(occ, a: np.ndarray, b: np.ndarray, w: float, h: float) -> int:
    """A box of width w (in plan) and depth h (z) from plan point a to b (z = 0), its ends
    extended by half a width so that it reaches into what it joins."""
    d = b[:2] - a[:2]
    L = float(np.hypot(*d))
    tag = occ.addBox(-w / 2, -w / 2, -h / 2, L + w, w, h)
    occ.rotate([(3, tag)], 0, 0, 0, 0, 0, 1, math.atan2(d[1], d[0]))
    occ.translate([(3, tag)], float(a[0]), float(a[1]), 0.0)
    return tag


def _solid(occ, f: np.ndarray, r: np.ndarray, bj: np.ndarray) -> int:
    """The bore-less solid: eyes, boss, legs and cross member fused (its volume tag)."""
    eyes = [occ.addCylinder(float(c[0]) - EYE_LEN / 2, float(c[1]), float(c[2]),
                            EYE_LEN, 0, 0, EYE_OD / 2) for c in (f, r)]
    boss = occ.addCylinder(float(bj[0]), float(bj[1]), float(bj[2]) - BOSS_H / 2,
                           0, 0, BOSS_H, BOSS_OD / 2)
    legs = [_bar(occ, c, bj, LEG_W, LEG_H) for c in (f, r)]
    # the cross member: between the legs' centre lines at y = CROSS_Y
    xs = [float(c[0] + (bj[0] - c[0]) * CROSS_Y / (bj[1] - c[1])) for c in (f, r)]
    cross = occ.addBox(min(xs), CROSS_Y - CROSS_W / 2, -CROSS_H / 2, abs(xs[0] - xs[1]),
                       CROSS_W, CROSS_H)
    solid, _ = occ.fuse([(3, eyes[0])], [(3, t) for t in (eyes[1], boss, *legs, cross)])
    occ.synchronize()
    assert len(solid) == 1, solid
    return int(solid[0][1])


def build(out: Path = OUT) -> dict:
    """Write the STEP; returns the solid's OCC volume [m^3], mass [kg] and edge counts."""
    import gmsh  # type: ignore[import-untyped]

    hp = hardpoints()
    f, r, bj = hp["upper_bush_front"], hp["upper_bush_rear"], hp["upper_ball_joint"]
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        occ = gmsh.model.occ
        vol_tag = _solid(occ, f, r, bj)
        vol0 = occ.getMass(3, vol_tag)
        # fillet the sharp re-entrant edges (where a leg or the cross member meets an eye,
        # the boss or the other leg: features.py finds them) in one pass, before the bores;
        # the eyes' junctions with the legs are left sharp (inside the bush joints' zones,
        # docs/parts.md), and any edge OCC refuses to fillet alone
        from nodes.fatigue.parts.features import sharp_reentrant_edges

        found = sharp_reentrant_edges(vol_tag)
        sharp = [e["curve"] for e in found]
        # not at the eyes: a fillet there ends tangent on the eye's cylinder, and gmsh meshed
        # a flat tetrahedron on that line (zero volume, at every size tried, 7-10 mm)
        away = [e["curve"] for e in found if min(
            np.hypot(*(np.asarray(e["midpoint_m"])[1:] - c[1:])) for c in (f, r))
            > EYE_OD / 2 + 0.002 or min(abs(e["midpoint_m"][0] - c[0]) for c in (f, r))
            > EYE_LEN / 2 + 0.002]
        keep = []
        for e in away:
            gmsh.model.remove()
            gmsh.model.add("trial")
            v = _solid(occ, f, r, bj)
            try:
                if len(occ.fillet([v], [e], [FILLET])) == 1:
                    keep.append(e)
            except Exception:  # gmsh raises a bare Exception for OCC's refusal
                pass
        gmsh.model.remove()
        gmsh.model.add("upper_arm")
        vol_tag = _solid(occ, f, r, bj)
        body = occ.fillet([vol_tag], keep, [FILLET])
        occ.synchronize()
        if len(body) != 1:
            raise RuntimeError(f"OCC fillet gave {len(body)} volumes on {len(keep)} edges")
        vol1 = occ.getMass(3, body[0][1])
        bores = [occ.addCylinder(float(c[0]) - EYE_LEN, float(c[1]), float(c[2]),
                                 2 * EYE_LEN, 0, 0, EYE_BORE / 2) for c in (f, r)]
        bores.append(occ.addCylinder(float(bj[0]), float(bj[1]), float(bj[2]) - BOSS_H,
                                     0, 0, 2 * BOSS_H, BOSS_BORE / 2))
        cut, _ = occ.cut(body, [(3, t) for t in bores])
        occ.synchronize()
        assert len(cut) == 1, cut
        vol = occ.getMass(3, cut[0][1])
        gmsh.option.setString("Geometry.OCCTargetUnit", "M")
        tmp = out.with_name(f".new-{out.name}")  # written aside, renamed into place
        gmsh.write(str(tmp))
        tmp.replace(out)
        left = sharp_reentrant_edges(cut[0][1])
        return {"volume_m3": vol, "mass_kg": vol * STEEL,
                "unfilleted_bore_less_kg": vol0 * STEEL, "filleted_bore_less_kg": vol1 * STEEL,
                "sharp_edges_before": len(sharp), "filleted_edges": len(keep),
                "sharp_edges_left": [[round(1e3 * x, 1) for x in e["midpoint_m"]]
                                     for e in left]}
    finally:
        gmsh.finalize()


def static_upper_arm_loads() -> dict[str, float]:
    """The plant's upper-arm loads at static ride height [N] (arm_card.static_plant_loads)."""
    from orchestrator.studies.arm_card import static_plant_loads

    return static_plant_loads()["upper_arm"]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--card", action="store_true",
                    help="also print the part file's model card (JSON) under the plant's "
                         "static upper-arm loads")
    ap.add_argument("--mesh-size", type=float, default=None)
    args = ap.parse_args()
    info = build(args.out)
    print(json.dumps(info, indent=2))
    if args.card:
        from nodes.fatigue.parts.card import card
        from nodes.fatigue.parts.schema import load_part

        part = load_part(args.out.with_suffix(".toml"))
        c, _, _ = card(part, static_upper_arm_loads(), args.mesh_size)
        print(json.dumps(c, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
