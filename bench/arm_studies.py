"""The design studies that produced the shipped arms (issues #12 and #26 item 2): the built-in
lower arm's CAD variants, fillets, mesh convergence and design space, and the upper wishbone's
STEP file. Their results are in docs/parts.md.

    python -m bench arm-cad-grid '[{"section.rib_depth_root": 0.046}, {...}]'   # CAD only
    python -m bench arm-fillet-order                                            # CAD only, ~1 min
    python -m bench arm-variant --size 0.03 --set section.rib_depth_root=0.047 [--modes 1]
    python -m bench arm-convergence [OUT.json] [--run RUN_DIR] [--local 0.005 0.0035]
                                    [--set section.hole_rib_width=[0.011,0.011,0.005]]
    python -m bench upper-arm-cad [--card] [--mesh-size 0.008] [--out STEP]

``arm-cad-grid``: which CAD variants of the built-in pivot-tube arm OpenCASCADE can fillet.
Each variant overrides the part file's CAD parameters (``data/lower_arm_cad.toml``;
"table.key": value, metres) and is built by ``cad_arm.build`` (one fillet pass before the
bores): OK with the forging's OCC mass (7850 kg/m^3) and the sharp re-entrant edges left, or
FAIL with OCC's message. A few seconds per variant.

``arm-fillet-order``: which fillets OCC can put on the pivot-tube arm, and in which order. The
pivot-tube variant (690 Hz, 5.42 kg) misses 3 g <= 0.8 yield at an unfilleted rib-eye junction
(a corner singularity no mesh converges). The unfilleted solid's sharp re-entrant edges are
split into web roots (in the web's planes) and junctions (ribs meeting the eye tubes and the
ball-joint housing, the pivot tube's bore steps); tried: every edge in one pass, then the
junctions first at ``R_JUNCTION`` and greedily as many web roots as OCC accepts at the
section's fillet radius. Prints the counts and the edges left.

``arm-variant``: one CAD variant (``--set table.key=JSON``) through the part card's FE: meshed
at ``--size`` (fillet size scaled as the card does), the unit cases and ``--modes`` modes
solved; mass, first mode, static hot spot, 3 g / yield, where the ten hot spots sit and the
wall time of each step (JSON). The part file: nodes/fatigue/parts/data/lower_arm.toml.

``arm-convergence``: the built-in arm's mesh-convergence table, logged mesh by mesh: as
``suscosim part check nodes/fatigue/parts/data/lower_arm.toml --convergence`` (the part file's
``mesh.convergence``, ``convergence_local``, ``convergence_radius``, the plant's static loads)
without the card's own mesh and modes; the table as JSON (to OUT, written aside and renamed,
and stdout). ``--run RUN_DIR``: each mesh's damage under that run's loads (every node, no
screening); the refinement also takes the global mesh's most damaged nodes in. The last lines
are the part file's ``[mesh]`` keys for the balls (``refine_centres``).

``upper-arm-cad``: makes the upper wishbone's STEP (nodes/fatigue/parts/data/upper_arm.step)
with gmsh's OpenCASCADE kernel (docs/parts.md, "A second part: the upper wishbone"): a forged
A-arm in the frame of ``plant/upper_arm`` (origin the upper bushes' midpoint, x along the pivot
axis, y toward the ball joint), its centres the corner file's upper hardpoints; two bush eyes, a
ball-joint boss, two legs and a cross member, filleted where they meet (not at the eyes), the
bores cut after the fillets. ``--card``: its model card under the plant's static loads.
"""

from __future__ import annotations

import argparse
import copy
import json
import math
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from nodes.fatigue.parts import cad_arm  # noqa: E402
from nodes.fatigue.parts.features import sharp_reentrant_edges  # noqa: E402
from nodes.fatigue.parts.hardpoints import hardpoints  # noqa: E402


# ---- arm-cad-grid ---------------------------------------------------------------------------
def cad_grid(args: argparse.Namespace) -> int:
    """``arm-cad-grid``: build each CAD variant; OK (mass, sharp edges) or FAIL."""
    import gmsh  # type: ignore[import-untyped]

    base = cad_arm.load_params()
    gmsh.initialize(interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        for v in json.loads(args.variants):
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
    return 0


# ---- arm-fillet-order -----------------------------------------------------------------------
R_JUNCTION = 0.003
"""Junction fillet radius [m] (5 mm breaks on the pivot tube's 3 mm bore steps)."""


def _fo_variant(d0: float, d1: float, boss: float) -> dict[str, Any]:
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


def fillet_order(args: argparse.Namespace) -> int:
    """``arm-fillet-order``: the fillet passes OCC accepts on three variants."""
    print("| variant | web roots / junctions (unfilleted) | one pass ok | junctions first "
          "(3 mm) | web roots then (5 mm, greedy) |")
    print("|---|---|---|---|---|")
    for name, dims in (("ribs 36/32 mm, boss 29 mm", (0.036, 0.032, 0.029)),
                       ("ribs 46/32 mm, boss 29 mm", (0.046, 0.032, 0.029)),
                       ("ribs 36/26 mm, boss 25 mm", (0.036, 0.026, 0.025))):
        print(trial(name, _fo_variant(*dims)), flush=True)
    return 0


# ---- arm-variant ----------------------------------------------------------------------------
def arm_variant(args: argparse.Namespace) -> int:
    """``arm-variant``: one CAD variant through the part card's FE."""
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
    return 0


# ---- arm-convergence ------------------------------------------------------------------------
def damage_of_run(run_dir: Path, part_path: Path):
    """A function InfluenceSet -> damage per node for one pass of the run's loads."""
    import pyarrow.parquet as pq

    from nodes.fatigue import worker
    from nodes.fatigue.config import FatigueConfig
    from nodes.fatigue.run_dir import track_length

    scenario = json.loads((run_dir / "scenario.json").read_text())
    section = dict(scenario.get("fatigue") or {})
    section["influence"] = str(part_path)
    cfg = FatigueConfig.from_dict(section, "fatigue", base_dir=run_dir)
    tab = pq.read_table(run_dir / "table.parquet")
    t = np.asarray(tab.column("t"), dtype=float)
    loads = {c: np.asarray(tab.column(c), dtype=float) for c in tab.column_names
             if c.startswith("plant/arm/")}
    L = track_length(scenario, t)

    def damage(inf):
        orig = worker.load_influence
        worker.load_influence = lambda _cfg: inf
        try:
            return worker.analyse(t, loads, cfg, L).damage
        finally:
            worker.load_influence = orig
    return damage


def arm_convergence(args: argparse.Namespace) -> int:
    """``arm-convergence``: the built-in arm's mesh-convergence table."""
    from nodes.fatigue.parts.card import convergence
    from nodes.fatigue.parts.data import __file__ as _data
    from nodes.fatigue.parts.schema import load_part
    from orchestrator.studies.arm_card import static_arm_loads

    if args.set:
        params = cad_arm.load_params()
        for s in args.set:
            key, val = s.split("=", 1)
            table, k = key.split(".")
            params[table][k] = json.loads(val)
        cad_arm.load_params = lambda path=None: params  # type: ignore[assignment]
    path = Path(_data).parent / "lower_arm.toml"
    part = load_part(path)
    loads = {k: v for k, v in static_arm_loads().items() if k in part.channels}
    dmg = damage_of_run(args.run, path) if args.run else None
    cv = convergence(part, part.convergence, loads, local_sizes=args.local,
                     radius=args.radius, log=lambda s: print(s, flush=True), damage=dmg)
    text = json.dumps(cv, indent=2)
    if args.out is not None:
        tmp = args.out.with_name(args.out.name + f".{os.getpid()}.tmp")
        tmp.write_text(text)
        os.replace(tmp, args.out)
    print(text)
    rf = cv.get("refinement")
    if rf:
        print("refine_centres = [" + ", ".join(
            "[" + ", ".join(f"{v:.4f}" for v in c) + "]" for c in rf["centres_m"]) + "]")
        print(f"refine_radius = {rf['radius_m']}")
    return 0


# ---- upper-arm-cad --------------------------------------------------------------------------
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


def upper_arm_cad(args: argparse.Namespace) -> int:
    """``upper-arm-cad``: write the upper wishbone's STEP (and print its card)."""
    info = build(args.out)
    print(json.dumps(info, indent=2))
    if args.card:
        from nodes.fatigue.parts.card import card
        from nodes.fatigue.parts.schema import load_part

        part = load_part(args.out.with_suffix(".toml"))
        c, _, _ = card(part, static_upper_arm_loads(), args.mesh_size)
        print(json.dumps(c, indent=2))
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("arm-cad-grid", help="which CAD variants of the arm OCC can fillet")
    p.add_argument("variants", help='a JSON list of {"table.key": value} overrides')
    p.set_defaults(fn=cad_grid)
    p = sub.add_parser("arm-fillet-order", help="which fillets OCC accepts, in which order")
    p.set_defaults(fn=fillet_order)
    p = sub.add_parser("arm-variant", help="one CAD variant through the part card's FE")
    p.add_argument("--size", type=float, default=0.03)
    p.add_argument("--modes", type=int, default=1)
    p.add_argument("--set", action="append", default=[], metavar="TABLE.KEY=JSON")
    p.set_defaults(fn=arm_variant)
    p = sub.add_parser("arm-convergence", help="the built-in arm's mesh-convergence table")
    p.add_argument("out", nargs="?", type=Path)
    p.add_argument("--run", type=Path, help="a recorded run folder: damage on every mesh")
    p.add_argument("--local", type=float, nargs="+", help="local sizes [m] (the part file's "
                                                         "convergence_local by default)")
    p.add_argument("--radius", type=float)
    p.add_argument("--set", action="append", default=[], metavar="TABLE.KEY=JSON",
                   help="override a CAD parameter of data/lower_arm_cad.toml (as "
                        "arm-variant): the table of a variant before adopting it")
    p.set_defaults(fn=arm_convergence)
    p = sub.add_parser("upper-arm-cad", help="make the upper wishbone's STEP file")
    p.add_argument("--out", type=Path, default=OUT)
    p.add_argument("--card", action="store_true",
                   help="also print the part file's model card (JSON) under the plant's "
                        "static upper-arm loads")
    p.add_argument("--mesh-size", type=float, default=None)
    p.set_defaults(fn=upper_arm_cad)
    args = ap.parse_args(argv)
    return int(args.fn(args) or 0)


if __name__ == "__main__":
    raise SystemExit(main())
