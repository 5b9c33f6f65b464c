"""``suscosim arm``: the built-in lower arm's model card, from its shipped results: reads the
results beside nodes/fatigue/parts/data/lower_arm.toml (no meshing, no solve) and
prints (or ``--json``): mass, the first six free-free modes, the hot-spot stress under the
static wheel load (the double-wishbone plant's joint loads at static equilibrium, so the card
and the runs see the same arm; inertia relief) with its node, 3 g vertical (static x 3,
quasi-static), yield, the mesh and the mode-stress floor (nodes/fatigue/lib/arm_bounds.py).
``suscosim part`` meshes and solves a part.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from cosim import lower_arm as arm
from cosim.errors import InputFileError, ScenarioError

TABLE_6_1_M1_HZ = 362.3  # [Hz] Table 6.1's first flexible mode (vertical bending)
LEG_LENGTH = 0.32  # [m] pivot to ball joint (front 0.312, rear 0.332): the floor's beam


def static_plant_loads() -> dict[str, dict[str, float]]:
    """Each plant load channel's fields at static ride height [N, N m] (double wishbone)."""
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
    return static_plant_loads()["arm"]


def stress_floor(moment: float, mass: float, mat) -> dict[str, float]:
    """Least nominal bending stress [MPa] for M1 at Table 6.1's 362 Hz and +15 % (κ = 1)."""
    from nodes.fatigue.lib.arm_bounds import nominal_bending_stress as sigma

    return {f"at_{f:.0f}_hz": sigma(moment, mass, LEG_LENGTH, f, mat.E, mat.rho) / 1e6
            for f in (TABLE_6_1_M1_HZ, 1.15 * TABLE_6_1_M1_HZ)}


def card() -> dict:
    from nodes.fatigue.config import BUILTIN_PART
    from nodes.fatigue.lib.equivalent_stress import von_mises
    from nodes.fatigue.materials import steel_817M40
    from nodes.fatigue.parts import load_part
    from nodes.fatigue.parts.results_file import part_results

    mat = steel_817M40()
    inf = part_results(load_part(BUILTIN_PART))
    loads = static_arm_loads()
    f = np.array([loads.get(c, 0.0) for c in inf.case_names])
    vm = von_mises(np.einsum("c,cnk->nk", f, inf.coefficients))
    i = int(np.argmax(vm))  # every node of a part's results is assessed
    assert inf.node_xyz is not None  # a part's FE always has its node coordinates
    meta = inf.meta
    floor = stress_floor(abs(loads.get("torsion_bar_mx", 0.0)), meta["mass_kg"], mat)
    return {
        "part": str(BUILTIN_PART.name),
        "mass_kg": meta["mass_kg"],
        "mass_table_4_2_kg": arm.MASS_KG,
        "modes_hz": meta["natural_frequencies_hz"],
        "mode_1_table_6_1_hz": TABLE_6_1_M1_HZ,
        "stress_floor_mpa": floor,
        "static_hotspot_stress_mpa": float(vm[i]) / 1e6,
        "static_hotspot_node": int(inf.node_ids[i]),
        "static_hotspot_xyz_m": [float(v) for v in inf.node_xyz[i]],
        "max_stress_3g_mpa": 3.0 * float(vm[i]) / 1e6,
        "yield_mpa": mat.Sy / 1e6,
        "static_loads": loads,
        "mesh_size_m": meta["mesh_size_m"],
        "n_elements": meta["n_elements"],
        "n_nodes": meta["n_nodes"],
        "n_nodes_assessed": inf.n_nodes,
        "element": meta["element"],
        "supports": meta["supports"],
        "load_cases": list(inf.case_names),
        "material": mat.name,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="suscosim arm", description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print the card as JSON")
    args = ap.parse_args(argv)
    try:
        c = card()
    except (InputFileError, ScenarioError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(c, indent=2))
        return 0
    x, y, z = c["static_hotspot_xyz_m"]
    print(f"lower arm ({c['material']}; the part file {c['part']}, its shipped results)")
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
    print(f"  mesh {c['mesh_size_m'] * 1e3:.0f} mm: {c['n_elements']} elements, {c['n_nodes']} "
          f"nodes ({c['n_nodes_assessed']} assessed), {c['element']}; {c['supports']}")
    return 0
