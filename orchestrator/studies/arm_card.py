"""``suscosim arm``: the lower arm's model card (FE of `cosim.lower_arm`).

Prints (or ``--json``): mass, the first six free-free flexible modes, the hot-spot stress under
the static wheel load (the plant's joint loads at static equilibrium, superposed on the unit
cases with inertia relief) with its node and position, the largest stress under a 3 g vertical
bump (the static load set times 3, quasi-static), the yield strength, the mesh, and a hand
calculation of the nominal bending stress across the legs beside the FE's.

The static loads come from the realistic corner itself (``nodes.plant.double_wishbone``: a
few substeps at the static tyre load, where the joint sensors are valid), so the card and the
runs see the same arm.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from cosim import lower_arm as arm
from cosim.errors import ScenarioError

TABLE_6_1_M1_HZ = 362.3
"""Table 6.1's first flexible mode of the thesis's arm (fundamental vertical bending) [Hz]."""
LEG_LENGTH = 0.32
"""Pivot to ball joint along the legs [m] (front 0.312, rear 0.332): the beam length of the
mode-stress floor (nodes/fatigue/arm_bounds.py)."""

NOMINAL_CUT_Y = 0.12
"""Distance from the pivot axis [m] of the cut across both legs for the hand calculation:
mid-way between the eyes' joint zones and the damper seat, where beam theory holds."""


def static_plant_loads() -> dict[str, dict[str, float]]:
    """Each plant load channel's fields at static ride height [N, N m] (``arm``: the lower
    arm's, ``upper_arm``: the upper arm's), from the double-wishbone plant model."""
    from nodes.plant.double_wishbone import DoubleWishboneCorner

    corner = DoubleWishboneCorner()
    try:
        W = corner.static_tyre_load()
        for _ in range(3):
            corner.substep(0.00025, W, np.zeros(1))
        return {ch: dict(v) for ch, v in corner.loads().items()}
    finally:
        corner.close()


def static_arm_loads() -> dict[str, float]:
    """Joint loads on the lower arm at static ride height [N, N m], from the plant model."""
    return static_plant_loads()["arm"]


def section_depths(y_cut: float, n: int = 4001) -> tuple[np.ndarray, np.ndarray]:
    """(x [m], depth [m]) along the cut y = y_cut through the arm's solid (hole excluded)."""
    from matplotlib.path import Path

    from nodes.fatigue.arm_mesh import hole, outline

    x = np.linspace(-0.3, 0.3, n)
    pts = np.c_[x, np.full(n, y_cut)]
    inside = Path(outline()).contains_points(pts) & ~Path(hole()).contains_points(pts)
    depth = np.where(inside, arm.WEB_DEPTH, 0.0)
    # ribs: within the rib widths of the outline or the hole edge
    d_out = _distance_to_polyline(pts, outline())
    d_hole = _distance_to_polyline(pts, hole())
    rib = inside & ((d_out <= arm.OUTER_RIB_WIDTH) | (d_hole <= arm.HOLE_RIB_WIDTH))
    depth = np.where(rib, arm.rib_depth(x, np.full(n, y_cut)), depth)
    depth = np.where(inside, np.maximum(depth, arm.boss_depth(x, np.full(n, y_cut))), 0.0)
    return x, depth


def _distance_to_polyline(pts: np.ndarray, poly: np.ndarray) -> np.ndarray:
    a = poly
    b = np.roll(poly, -1, axis=0)
    ab = b - a
    t = np.clip(((pts[:, None, :] - a) * ab).sum(-1) / (ab * ab).sum(-1), 0.0, 1.0)
    proj = a + t[..., None] * ab
    return np.min(np.linalg.norm(pts[:, None, :] - proj, axis=-1), axis=1)


def nominal_bending_stress(loads: dict[str, float], y_cut: float = NOMINAL_CUT_Y) -> dict:
    """Beam theory across both legs at y = y_cut: M_x of the loads outboard of the cut (ball
    joint, damper seat, bump-stop pad) about the cut's neutral axis (z = 0, the section is
    symmetric), I = ∫ d(x)³ / 12 dx over the cut, σ = -M c / I at the top of the deepest rib
    (c = d_max / 2; compression on top for the upward wheel load) [Pa]."""
    x, d = section_depths(y_cut)
    dx = x[1] - x[0]
    inertia = float(np.sum(d ** 3) / 12.0 * dx)
    moment = 0.0
    for name in ("ball_joint", "damper_mount", "bump_stop"):
        p = arm.HARDPOINTS[name]
        if p[1] <= y_cut:
            continue
        fz = loads.get(f"{name}_z", 0.0)
        fy = loads.get(f"{name}_y", 0.0)
        moment += (p[1] - y_cut) * fz - p[2] * fy  # (r x F)_x about (., y_cut, 0)
    c = 0.5 * float(d.max())
    return {"y_cut_m": y_cut, "moment_nm": moment, "second_moment_m4": inertia,
            "half_depth_m": c, "sigma_pa": -moment * c / inertia}


def fe_bending_stress(inf, loads: dict[str, float], y_cut: float = NOMINAL_CUT_Y,
                      band: float = 0.010) -> float:
    """The FE's bending stress [Pa] on the top of the ribs at the cut: the signed largest
    principal stress (at a rib's top fibre the stress is uniaxial along the leg) averaged over
    the top-surface nodes within ``band`` of y_cut whose depth is within 10 % of the deepest.

    Beam theory across oblique legs: each leg carries the moment's component along its own
    transverse axis, M cos θ, on a section cos θ narrower than the cut, so the stress along the
    leg is M c / I_cut whatever θ (the moment's other component twists the legs)."""
    from nodes.fatigue.equivalent_stress import abs_max_principal

    f = np.array([loads.get(c, 0.0) for c in inf.case_names])
    S = np.einsum("c,cnk->nk", f, inf.coefficients)
    xyz = inf.node_xyz
    near = np.abs(xyz[:, 1] - y_cut) <= band
    ztop = xyz[:, 2]
    top = near & (ztop >= 0.9 * ztop[near].max())
    return float(abs_max_principal(S[top]).mean())


def stress_floor(moment: float, mass: float, mat) -> dict[str, float]:
    """The least nominal bending stress [MPa] an arm of this mass can carry the torsion
    spring's static moment at, if its first vertical bending mode is at Table 6.1's 362 Hz and
    at its +15 % (nodes/fatigue/arm_bounds.py, ideal section κ = 1): why a 5 kg arm with the
    thesis's M1 cannot also keep its static hot spot under 250 MPa."""
    from nodes.fatigue.arm_bounds import nominal_bending_stress as sigma

    return {f"at_{f:.0f}_hz": sigma(moment, mass, LEG_LENGTH, f, mat.E, mat.rho) / 1e6
            for f in (TABLE_6_1_M1_HZ, 1.15 * TABLE_6_1_M1_HZ)}


def card(mesh_size: float = 0.02, modes: bool = True) -> dict:
    """The model card as a dict (SI inside, MPa where the key says so)."""
    from nodes.fatigue.equivalent_stress import von_mises
    from nodes.fatigue.influence import builtin_influence, joint_zone_nodes
    from nodes.fatigue.material import steel_817M40

    mat = steel_817M40()
    inf = builtin_influence(mesh_size, mat)
    loads = static_arm_loads()
    f = np.array([loads.get(c, 0.0) for c in inf.case_names])
    S = np.einsum("c,cnk->nk", f, inf.coefficients)
    vm = von_mises(S)
    assessed = inf.surface
    i = int(np.argmax(np.where(assessed, vm, -1.0)))
    xyz = inf.node_xyz
    assert xyz is not None  # the built-in FE always has its node coordinates
    zone = joint_zone_nodes(xyz) & ~assessed
    j = int(np.argmax(np.where(zone, vm, -1.0))) if zone.any() else i
    hand = nominal_bending_stress(loads)
    meta = inf.meta
    floor = stress_floor(abs(loads.get("torsion_bar_mx", 0.0)), meta["mass_kg"], mat)
    return {
        "mass_kg": meta["mass_kg"],
        "mass_table_4_2_kg": arm.MASS_KG,
        "modes_hz": meta["natural_frequencies_hz"] if modes else None,
        "mode_1_table_6_1_hz": TABLE_6_1_M1_HZ,
        "stress_floor_mpa": floor,
        "static_hotspot_stress_mpa": float(vm[i]) / 1e6,
        "static_hotspot_node": int(inf.node_ids[i]),
        "static_hotspot_xyz_m": [float(v) for v in xyz[i]],
        "static_joint_zone_peak_mpa": float(vm[j]) / 1e6,
        "max_stress_3g_mpa": 3.0 * float(vm[i]) / 1e6,
        "yield_mpa": mat.Sy / 1e6,
        "static_loads": loads,
        "nominal_bending": {**hand, "sigma_mpa": hand["sigma_pa"] / 1e6,
                            "fe_sigma_mpa": fe_bending_stress(inf, loads) / 1e6},
        "mesh_size_m": meta["mesh_size_m"],
        "n_elements": meta["n_elements"],
        "n_nodes": meta["n_nodes"],
        "n_nodes_assessed": int(assessed.sum()),
        "element": meta["element"],
        "supports": meta["supports"],
        "load_cases": list(inf.case_names),
        "material": mat.name,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="suscosim arm", description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print the card as JSON")
    ap.add_argument("--mesh-size", type=float, default=0.02, metavar="M",
                    help="FE element size [m] (default 0.02, the fatigue default)")
    args = ap.parse_args(argv)
    if not 0.005 <= args.mesh_size <= 0.05:
        print(f"error: --mesh-size {args.mesh_size}: expected 0.005-0.05 m", file=sys.stderr)
        return 2
    try:
        c = card(args.mesh_size)
    except ScenarioError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(c, indent=2))
        return 0
    nb = c["nominal_bending"]
    x, y, z = c["static_hotspot_xyz_m"]
    print(f"lower arm ({c['material']}, forged H-section; geometry cosim/lower_arm.py)")
    print(f"  mass                 {c['mass_kg']:.2f} kg"
          f"   (Table 4.2: {c['mass_table_4_2_kg']} kg)")
    print("  free-free modes      " + " ".join(f"{v:.0f}" for v in c["modes_hz"])
          + f" Hz   (Table 6.1 M1: {c['mode_1_table_6_1_hz']} Hz)")
    print(f"  static hot spot      {c['static_hotspot_stress_mpa']:.0f} MPa von Mises at node "
          f"{c['static_hotspot_node']} ({x * 1e3:.0f}, {y * 1e3:.0f}, {z * 1e3:.0f}) mm")
    print(f"  3 g vertical         {c['max_stress_3g_mpa']:.0f} MPa   (yield {c['yield_mpa']:.0f})")
    fl = c["stress_floor_mpa"]
    print("  stress floor if M1 were Table 6.1's vertical bending (362 / 416 Hz): "
          + " / ".join(f"{v:.0f}" for v in fl.values()) + " MPa nominal (arm_bounds)")
    print(f"  joint zones (not assessed) peak {c['static_joint_zone_peak_mpa']:.0f} MPa")
    print(f"  nominal bending at y = {nb['y_cut_m'] * 1e3:.0f} mm: hand {nb['sigma_mpa']:.1f} MPa,"
          f" FE {nb['fe_sigma_mpa']:.1f} MPa")
    print(f"  mesh {c['mesh_size_m'] * 1e3:.0f} mm: {c['n_elements']} elements, {c['n_nodes']} "
          f"nodes ({c['n_nodes_assessed']} assessed), {c['element']}; {c['supports']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
