"""The built-in arm's mesh-convergence table (#26 item 2), logged mesh by mesh.

    python bench/arm_convergence.py [OUT.json] [--run RUN_DIR] [--local 0.005 0.0035] \
        [--set section.hole_rib_width=[0.011,0.011,0.005]]

The same computation as ``suscosim part check nodes/fatigue/parts/data/lower_arm.toml
--convergence`` (``card.convergence`` with the part file's ``mesh.convergence``,
``convergence_local`` and ``convergence_radius``, the plant's static loads) without the card's
own mesh and six modes; prints a line per mesh as it is solved and the table as JSON (to OUT,
written aside and renamed, and to stdout). ``--run RUN_DIR``: a recorded run (its
``table.parquet`` and ``scenario.json``'s fatigue settings); each mesh's damage under its
loads is computed (``nodes.fatigue.worker.analyse``, every node, no screening), the
refinement also takes in the global mesh's most damaged nodes and the table reports the
finest mesh's ten most damaged nodes too. The last lines printed are the part file's
``[mesh]`` recipe keys for the balls (``refine_centres``).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from nodes.fatigue.parts.card import convergence  # noqa: E402
from nodes.fatigue.parts.data import __file__ as _data  # noqa: E402
from nodes.fatigue.parts.schema import load_part  # noqa: E402
from orchestrator.studies.arm_card import static_arm_loads  # noqa: E402


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


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("out", nargs="?", type=Path)
    ap.add_argument("--run", type=Path, help="a recorded run folder: damage on every mesh")
    ap.add_argument("--local", type=float, nargs="+", help="local sizes [m] (the part file's "
                                                          "convergence_local by default)")
    ap.add_argument("--radius", type=float)
    ap.add_argument("--set", action="append", default=[], metavar="TABLE.KEY=JSON",
                    help="override a CAD parameter of data/lower_arm_cad.toml (as "
                         "bench/arm_variant.py): the table of a variant before adopting it")
    args = ap.parse_args()
    if args.set:
        from nodes.fatigue.parts import cad_arm

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


if __name__ == "__main__":
    main()
