"""``suscosim part check PART.toml [--json] [--mesh-size M] [--convergence] [--calculix]``:
a part file's model card (nodes/fatigue/parts/card.py; docs/parts.md) under the plant's static
joint loads (3 g = 3 x static; without loads: mass, modes, mesh); ``--calculix``: the largest
difference to ccx at the ten hot spots. ``part solve``: its results file. Exit 2: a bad file.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np

from cosim.errors import InputFileError, ScenarioError

from ..cli_util import fail


def _static_loads(channels: list[str]) -> dict[str, float]:
    from .arm_card import static_plant_loads

    return {k: v for fields in static_plant_loads().values() for k, v in fields.items()
            if k in channels}


def check(args: argparse.Namespace) -> int:
    from nodes.fatigue.lib.equivalent_stress import von_mises
    from nodes.fatigue.parts.card import card, convergence
    from nodes.fatigue.parts.schema import load_part

    part = load_part(args.part)
    loads = _static_loads(part.channels)
    c, pm, ex = card(part, loads, args.mesh_size)
    if args.convergence and loads:
        c["convergence"] = convergence(part, part.convergence, loads)
    if args.calculix and "hot_spots" in c:
        from nodes.fatigue.parts.calculix import calculix_unit_cases

        with tempfile.TemporaryDirectory(prefix="suscosim-ccx-") as tmp:
            names, S = calculix_unit_cases(pm, Path(tmp))
        idx = [h["index"] for h in c["hot_spots"]]
        rel = []
        for k in range(len(names)):
            ours = von_mises(ex["coef"][k][idx])
            ref = max(float(ours.max()), 1e-30)
            rel.append(float(np.abs(von_mises(S[k][idx]) - ours).max() / ref))
        c["calculix_max_rel_diff_at_hot_spots"] = max(rel)
    if args.json:
        print(json.dumps(c, indent=2))
        return 0
    print(f"part {c['part']} ({c['material']}; {c['geometry']})")
    print(f"  mass              {c['mass_kg']:.3f} kg (solid {c['solid_mass_kg']:.3f} + "
          f"hardware {c['hardware_mass_kg']:.3f})")
    x, y, z = (1e3 * v for v in c["centre_of_mass_m"])
    print(f"  centre of mass    ({x:.1f}, {y:.1f}, {z:.1f}) mm")
    print("  free-free modes   " + ", ".join(f"{m['hz']:.0f} Hz {m['shape']}"
                                             for m in c["modes"]))
    if "hot_spots" in c:
        h = c["hot_spots"][0]
        hx, hy, hz = (1e3 * v for v in h["xyz_m"])
        print(f"  static hot spot   {h['von_mises_mpa']:.0f} MPa von Mises at node {h['node']} "
              f"({hx:.1f}, {hy:.1f}, {hz:.1f}) mm")
        print(f"  3 g vertical      {c['max_stress_3g_mpa']:.0f} MPa = "
              f"{c['ratio_3g_to_yield']:.2f} x yield ({c['yield_mpa']:.0f} MPa)")
        print("  hot spots (static, MPa; mm to the nearest sharp re-entrant edge):")
        for h in c["hot_spots"]:
            hx, hy, hz = (1e3 * v for v in h["xyz_m"])
            d = h["distance_to_sharp_edge_m"] * 1e3
            flag = "  ON A SHARP RE-ENTRANT EDGE" if h["on_sharp_reentrant_edge"] else ""
            print(f"    node {h['node']:>7}  ({hx:7.1f}, {hy:7.1f}, {hz:6.1f})  "
                  f"{h['von_mises_mpa']:6.0f}  {d:6.1f}{flag}")
        if c["static_joint_zone_peak_mpa"] is not None:
            print(f"  joint zones (not assessed) peak {c['static_joint_zone_peak_mpa']:.0f} MPa")
    else:
        print("  (no static loads: the plant publishes none of this part's channels)")
    print(f"  joint zones: {c['joint_zone_rule']}")
    for name, j in c["joints"].items():
        print(f"    {name:<14} {j['nodes']:>5} nodes, {j['coupling']}, zone {j['zone_m'] * 1e3:.0f}"
              f" mm, hardware {j['mass_kg']:.2f} kg")
    print(f"  mesh {c['mesh_size_m'] * 1e3:.1f} mm (fillets {c['fillet_size_m'] * 1e3:.1f} mm):"
          f" {c['n_elements']} elements, {c['n_nodes']} nodes ({c['n_nodes_assessed']} "
          f"assessed), {c['element']}; {c['supports']}")
    if "convergence" in c:
        cv = c["convergence"]
        print("  convergence   size  local   nodes  mass kg  mode 1 Hz  static hot spot MPa")
        for r in cv["rows"]:
            loc = "-" if r.get("local_size_m") is None else f"{r['local_size_m'] * 1e3:.1f}"
            print(f"             {r['size_m'] * 1e3:5.1f} {loc:>6} {r['n_nodes']:>7} "
                  f"{r['mass_kg']:8.3f} {r['mode_1_hz']:10.0f} "
                  f"{r['static_hotspot_mpa']:10.0f}")
        rf = cv.get("refinement")
        if rf is not None:
            out = ("-" if rf["peak_outside_mpa"] is None
                   else f"{rf['peak_outside_mpa']:.0f} MPa")
            print(f"  local refinement: {rf['n_balls']} balls of {rf['radius_m'] * 1e3:.0f} mm "
                  f"round the nodes >= {rf['fraction']:.1f} x the hot spot; ten hot spots "
                  f"inside: {'yes' if rf['hot_spots_inside'] else 'NO'}; highest assessed "
                  f"stress outside: {out} (tenth hot spot {rf['tenth_hot_spot_mpa']:.0f} MPa)")
        if cv["unit_change_two_finest"] is not None:
            print("  unit-load stress change, two finest meshes, at the ten hot spots: "
                  + " ".join(f"{100 * v:.1f}" for v in cv["unit_change_two_finest"]) + " %")
    if "calculix_max_rel_diff_at_hot_spots" in c:
        print(f"  CalculiX (same mesh, unit cases): largest difference at the hot spots "
              f"{100 * c['calculix_max_rel_diff_at_hot_spots']:.4f} %")
    return 0


def solve(args: argparse.Namespace) -> int:
    import time

    from nodes.fatigue.parts import load_part
    from nodes.fatigue.parts.build import part_model, solve_part
    from nodes.fatigue.parts.results_file import current_key, write_results

    part = load_part(args.part)
    t0 = time.perf_counter()
    size = part.mesh_size if args.mesh_size is None else args.mesh_size
    pm = part_model(part, size, part.fillet_size * size / part.mesh_size)
    inf, _ = solve_part(pm)
    key = current_key(part, args.mesh_size)
    path = write_results(part, inf, key, args.out)
    print(f"{part.name}: {pm.fe.n_nodes} P2 nodes, {inf.n_nodes} assessed, "
          f"{len(inf.case_names)} unit cases, key {key}, {time.perf_counter() - t0:.0f} s "
          f"-> {path}")
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="suscosim part", description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("part", help="part file (TOML)")
    common.add_argument("--mesh-size", type=float, default=None, metavar="M",
                        help="element size [m] (default: the part file's mesh.size)")
    ck = sub.add_parser("check", help="print a part's model card", parents=[common])
    ck.add_argument("--json", action="store_true", help="print the card as JSON")
    ck.add_argument("--convergence", action="store_true",
                    help="also solve the part file's mesh.convergence sizes (slow)")
    ck.add_argument("--calculix", action="store_true",
                    help="also solve the unit cases with CalculiX (ccx) and compare")
    sv = sub.add_parser("solve", help="solve a part's unit cases and write its results file "
                                      "beside it (PART.influence.npz), which runs then use",
                        parents=[common])
    sv.add_argument("--out", type=Path, default=None,
                    help="results file (default: beside the part file)")
    args = ap.parse_args(argv)
    if args.mesh_size is not None and not 1e-4 <= args.mesh_size <= 1.0:
        return fail("suscosim part", f"--mesh-size {args.mesh_size}: expected 0.0001-1 m")
    try:
        return solve(args) if args.cmd == "solve" else check(args)
    except (InputFileError, ScenarioError) as exc:
        return fail("suscosim part", str(exc))


if __name__ == "__main__":
    raise SystemExit(main())
