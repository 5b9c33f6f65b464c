"""``suscosim pseudo-damage SOURCE [SOURCE ...] [--k 5] [--n-ref 1e6] [--json]``: the
pseudo-damage of the load channels of run folders (``plant/arm/...``) or load files (every
channel, its own unit), side by side: per channel the rainflow cycles (ASTM half cycles for the
residue), D = Σ n (ΔF / 1 kN)^k / N_ref, the damage-equivalent range ΔF_eq at N_ref
(:mod:`nodes.fatigue.lib.pseudo_damage`), each source's ratio D / D_first. Exit 2: bad input.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from cosim.errors import SuscosimError

from .cli_util import fail, parse_args


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="suscosim pseudo-damage",
                                description="pseudo-damage of load channels, side by side")
    p.add_argument("sources", nargs="+", type=Path, metavar="RUN_DIR|LOAD_FILE")
    p.add_argument("--k", type=float, default=5.0,
                   help="slope of the reference S-N line (default 5: FKM non-welded steel)")
    p.add_argument("--n-ref", type=float, default=1e6, help="reference cycles (default 1e6)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    return p


def source_loads(src: Path) -> dict[str, np.ndarray]:
    """A run folder's arm load columns, or every channel of a load file."""
    if src.is_dir():
        from nodes.fatigue.run_dir import read_table

        return read_table(src)[1]
    from cosim.errors import InputFileError
    from cosim.formats import read_channels

    if not src.is_file():
        raise InputFileError(str(src), "no such run folder or load file")
    cs = read_channels(src)
    return {k: np.asarray(v, dtype=float) for k, v in cs.channels.items()}


def compare(sources: Sequence[Path], k: float = 5.0, n_ref: float = 1e6) -> dict:
    """{"k", "n_ref", "sources": [...], "channels": {name: [{d, eq_range, ratio}, ...]}}."""
    from nodes.fatigue.lib.pseudo_damage import channel_pseudo_damage

    per = [{p.channel: p for p in channel_pseudo_damage(source_loads(s), k, "half_cycles",
                                                         n_ref)} for s in sources]
    table: dict[str, list] = {}
    for n in dict.fromkeys(n for d in per for n in d):
        first = per[0].get(n)
        table[n] = [None if p is None else {
            "pseudo_damage": p.pseudo_damage, "equivalent_range": p.equivalent_range,
            "cycles": p.cycles, "max_range": p.max_range,
            "ratio_to_first": (p.pseudo_damage / first.pseudo_damage
                               if first is not None and first.pseudo_damage > 0 else None)}
            for p in (d.get(n) for d in per)]
    return {"k": k, "n_ref": n_ref, "ref_range": 1000.0,
            "sources": [str(s) for s in sources], "channels": table}


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(build_parser(), argv)
    if isinstance(args, int):
        return args
    if not (args.k > 0 and args.n_ref > 0):
        return fail("suscosim pseudo-damage", "--k and --n-ref must be > 0")
    try:
        res = compare(args.sources, args.k, args.n_ref)
    except SuscosimError as exc:
        return fail("suscosim pseudo-damage", str(exc))
    if args.json:
        print(json.dumps(res, indent=1))
        return 0
    heads = [s.name or str(s) for s in args.sources]
    print(f"pseudo-damage, k = {args.k:g}, reference 1 kN (kN m) range at "
          f"{args.n_ref:g} cycles; ratio to {heads[0]}")
    print(f"{'channel':<28}" + "".join(f"{h[:22]:>24}" for h in heads))
    for n, row in res["channels"].items():
        cells = []
        for e in row:
            if e is None:
                cells.append(f"{'-':>24}")
            elif e["ratio_to_first"] is None or e is row[0]:
                cells.append(f"{e['pseudo_damage']:>24.4e}")
            else:
                cells.append(f"{e['pseudo_damage']:>14.4e} ({e['ratio_to_first']:6.3g}x)")
        print(f"{n[-28:]:<28}" + "".join(cells))
    return 0
