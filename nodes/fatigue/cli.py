"""``suscosim fatigue RUN_DIR``: fatigue life of the lower arm from a finished run."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from cosim.errors import SuscosimError

from .config import RESIDUES
from .damage import METHODS
from .equivalent_stress import EQUIVALENTS
from .mean_stress import MEAN_STRESS_METHODS


def _value(text: str):
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="suscosim fatigue",
                                description="Fatigue life of the lower suspension arm of a run.")
    p.add_argument("run_dir", metavar="RUN_DIR", type=Path)
    p.add_argument("--equivalent", choices=EQUIVALENTS)
    p.add_argument("--method", choices=METHODS)
    p.add_argument("--mean-stress", choices=MEAN_STRESS_METHODS)
    p.add_argument("--residue", choices=RESIDUES)
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a fatigue key, e.g. --set material.sf=1.9e9 "
                        "--set mesh_size_m=0.03 (values parsed as JSON when possible)")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Run and print a short summary; 0 on success, 2 for bad input (one-line message)."""
    args = build_parser().parse_args(argv)
    overrides: dict = {}
    for item in args.set:
        if "=" not in item:
            print(f"error: --set expects KEY=VALUE, got {item!r}", file=sys.stderr)
            return 2
        k, v = item.split("=", 1)
        k = k.strip()
        if k.startswith("fatigue."):
            k = k[len("fatigue."):]
        overrides[k] = _value(v)
    for k in ("equivalent", "method", "mean_stress", "residue"):
        if getattr(args, k) is not None:
            overrides[k] = getattr(args, k)
    from .run_dir import fatigue_run_dir

    try:
        r = fatigue_run_dir(args.run_dir, overrides)
    except SuscosimError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return exc.exit_code if exc.exit_code else 2
    s = r.summary()
    xyz = r.critical_xyz
    where = "" if xyz is None else " at (" + ", ".join(f"{v * 1e3:.0f}" for v in xyz) + ") mm"
    print(f"fatigue: {s['n_nodes']} nodes, {r.n_samples} samples, track {r.track_length_m:.1f} m")
    print(f"  method {r.config['method']}, mean stress {r.config['mean_stress']}, "
          f"equivalent {r.config['equivalent']}")
    print(f"  min life {r.life_km:.4g} km = {r.life_repeats:.4g} repeats of the track"
          + ("" if r.life_repeats_basis is None
             else f" = {r.life_repeats_basis:.4g} repeats of {r.repeats_basis_m:g} m"))
    print(f"  critical node {r.critical_node_id}{where}, max damage/pass {r.max_damage:.3e}")
    print(f"  results in {Path(args.run_dir) / 'fatigue'}")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
