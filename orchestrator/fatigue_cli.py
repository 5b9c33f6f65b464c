"""``suscosim fatigue RUN_DIR | LOAD_FILE``: fatigue life of the lower arm of a finished run,
or under a load history (RPC III, MDF 4, CSV, Parquet) mapped to the arm's load channels (by
name, or ``--map SOURCE=TARGET[*SCALE]``) with the settings of ``--scenario``. A run's results
go to ``RUN_DIR/fatigue/``, or with settings (a what-if) to ``RUN_DIR/fatigue-<8 hex>/`` so the
live results stay; written aside and renamed into place. Exit codes: 0 a result (also "fails
on the first cycle": life 0 km); 2 bad input (one line naming it); 1 an internal error.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from cosim.errors import SuscosimError
from cosim.run_folder import read_json
from nodes.fatigue.config import RESIDUES
from nodes.fatigue.lib.critical_plane import CRITICAL_PLANES
from nodes.fatigue.lib.damage import METHODS
from nodes.fatigue.lib.equivalent_stress import EQUIVALENTS
from nodes.fatigue.lib.mean_stress import MEAN_STRESS_METHODS
from orchestrator.cli_util import fail, num, parse_args


def _value(text: str):
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="suscosim fatigue", description="Fatigue life of the lower "
                                "arm (and [fatigue] parts) of a run, or under a load file.")
    p.add_argument("run_dir", metavar="RUN_DIR|LOAD_FILE", type=Path)
    p.add_argument("--scenario", type=Path, metavar="RUN_DIR|SCENARIO",
                   help="load file only: take the fatigue settings and road length from this "
                        "run folder or scenario")
    p.add_argument("--map", action="append", default=[], metavar="SOURCE=TARGET[*SCALE]",
                   help="load file only: file channel SOURCE is the arm's load channel TARGET "
                        "(e.g. LCA_Fz=ball_joint_z*-1); by default channels are matched by "
                        "name (plant/arm/ball_joint_z or ball_joint_z)")
    p.add_argument("--out", type=Path, help="results folder (default LOAD_FILE.fatigue/, "
                                            "RUN_DIR/fatigue/, or RUN_DIR/fatigue-<hash>/)")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    p.add_argument("--equivalent", choices=(*EQUIVALENTS, *CRITICAL_PLANES),
                   help="findley: critical planes at the abs_max_principal pass's hot spots")
    p.add_argument("--method", choices=METHODS)
    p.add_argument("--mean-stress", choices=MEAN_STRESS_METHODS)
    p.add_argument("--residue", choices=RESIDUES)
    p.add_argument("--part", type=Path, metavar="PART.toml",
                   help="assess this part file (docs/parts.md) instead of the scenario's "
                        "influence and parts (a what-if); its joints give its load channel")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a fatigue key, e.g. --set material.sf=1.9e9 "
                        "--set mesh_size_m=0.03 (values parsed as JSON when possible)")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(build_parser(), argv)
    if isinstance(args, int):
        return args
    overrides: dict = {}
    for item in args.set:
        if "=" not in item:
            return fail("suscosim fatigue", f"--set expects KEY=VALUE, got {item!r}")
        k, v = item.split("=", 1)
        overrides[k.strip().removeprefix("fatigue.")] = _value(v)
    for k in ("equivalent", "method", "mean_stress", "residue"):
        if getattr(args, k) is not None:
            overrides[k] = getattr(args, k)
    if args.part is not None:
        if not args.part.is_file():
            return fail("suscosim fatigue", f"--part {args.part}: no such part file")
        overrides["influence"] = str(args.part.resolve())
        overrides["parts"] = []  # that part alone (not the scenario's [fatigue] parts)
    from nodes.fatigue.load_file import parse_map
    from nodes.fatigue.run_dir import fatigue_load_file, fatigue_run_dir, results_folder

    is_file = args.run_dir.is_file()
    if not is_file and (args.scenario or args.map):
        return fail("suscosim fatigue",
                    f"{args.run_dir}: --scenario and --map are for a load file")

    def progress(msg: str) -> None:
        if not args.quiet:
            print(msg, file=sys.stderr, flush=True)

    try:
        if is_file:
            out = args.out or args.run_dir.with_name(args.run_dir.name + ".fatigue")
            r = fatigue_load_file(args.run_dir, overrides, args.scenario,
                                  parse_map(args.map), out, progress)
        else:
            r = fatigue_run_dir(args.run_dir, overrides, args.out, progress)
            out = getattr(r, "results_dir", results_folder(args.run_dir, overrides, args.out))
    except SuscosimError as exc:
        return fail("suscosim fatigue", str(exc), exc.exit_code or 2)
    s = r.summary()
    xyz = r.critical_xyz
    where = "" if xyz is None else " at (" + ", ".join(f"{v * 1e3:.0f}" for v in xyz) + ") mm"
    print(f"fatigue: {s['n_nodes']} nodes, {r.n_samples} samples, track {r.track_length_m:.1f} m")
    print(f"  method {r.config['method']}, mean stress {r.config['mean_stress_applied']}, "
          f"equivalent {r.config['equivalent']}")
    summary = read_json(Path(out) / "summary.json")
    summary = summary if isinstance(summary, dict) else {}
    if summary.get("fails_first_cycle"):
        print("  fails on the first cycle: life 0 km (a cycle's mean-stress corrected "
              "stress is at or beyond the strength)")
    else:
        print(f"  min life {r.life_km:.4g} km = {r.life_repeats:.4g} repeats of the track"
              + ("" if r.life_repeats_basis is None
                 else f" = {r.life_repeats_basis:.4g} repeats of {r.repeats_basis_m:g} m")
              + _life_from(r.config))
    cp = summary.get("critical_plane") or {}
    if cp.get("hot_spots"):  # equivalent = "findley": its life is summary.json's headline
        h = cp["hot_spots"][0]
        print(f"  critical plane ({cp['method']}, {cp['hot_spots_assessed']} hot spots of "
              f"the line above): min life {num(h['life_km'])} km at node {h['node_id']}, normal ("
              + ", ".join(f"{v:.3f}" for v in h["normal"])
              + f"), rotation factor {h['rotation_factor']:.2f}")
    sm = summary.get("sn_methods") or {}
    for m, by_p in (sm.get("methods") or {}).items():
        print(f"  S-N {m} (mean stress {next(iter(by_p.values())).get('mean_stress')}): "
              + ", ".join(f"{v['life_km']:.4g} km at P = {p}"
                          if isinstance(v.get("life_km"), float)
                          else f"{v.get('life_km')} km at P = {p}" for p, v in by_p.items()))
    for m, why in (sm.get("left_out") or {}).items():
        print(f"  S-N {m}: not computed ({why})")
    print(f"  critical node {r.critical_node_id}{where}, max damage/pass {r.max_damage:.3e}")
    for p in (summary.get("parts") or [])[1:]:  # [fatigue] parts: each more part's headline
        print(f"  part {p.get('name')} ({p.get('load_channel')}): min life "
              f"{num(p.get('min_life_km'))} km, critical node "
              f"{p.get('critical_node_id')}, results in {Path(out) / str(p.get('folder'))}")
    if r.missing_channels:
        print("  no load given for " + ", ".join(r.missing_channels) + " (zero)")
    loaded = [u["channel"] for u in summary.get("unmapped_channels") or []
              if u.get("peak_abs")]
    if loaded:
        print("  warning: no influence case for " + ", ".join(loaded)
              + " (their loads are not in the stresses)")
    print(f"  results in {out}")
    return 0


def _life_from(config: dict) -> str:
    """``" (S-N fkm at P = 0.5, mean stress fkm)"``: the curve of the headline life, or ""."""
    comp = config.get("component") or {}
    if not comp.get("enabled") or config.get("sn_curve"):
        return ""
    return (f" (S-N {config.get('sn_method')} at P = {comp.get('reliability')!r}, "
            f"mean stress {config.get('mean_stress_applied')})")


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
