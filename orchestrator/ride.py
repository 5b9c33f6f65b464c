"""``suscosim ride RUN_DIR [RUN_DIR ...] [--baseline NAME] [--band LO HI] [--json]``: ride
metrics of finished runs, side by side (thesis Tables 5.3-5.6; docs/ch5_control_comparison.md):
:func:`nodes.recorder.ride_metrics.ride_table` (body RMS acceleration [m/s²] in band LO-HI Hz),
every run after the baseline (a folder name; default the first) with its % change (Eq 5.13,
positive = reduction). ``--json``: ``ride_summary`` plus each run's ``path``. Exit codes: 0
printed, 2 bad input.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

TABLE = "table.parquet"


def run_names(dirs: list[Path]) -> list[str]:
    """A unique display name per run folder: its name, or ``parent/name`` when two clash."""
    names = [d.name or str(d) for d in dirs]
    if len(set(names)) == len(names):
        return names
    full = [f"{d.parent.name}/{d.name}" for d in dirs]
    return full if len(set(full)) == len(full) else [str(d) for d in dirs]


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="suscosim ride",
                                 description="ride metrics of finished runs, side by side")
    ap.add_argument("runs", nargs="+", metavar="RUN_DIR", help="run folders (with table.parquet)")
    ap.add_argument("--baseline", metavar="NAME",
                    help="run (folder name) the others are compared with; default the first")
    ap.add_argument("--band", nargs=2, type=float, metavar=("LO", "HI"), default=(0.0, 20.0),
                    help="band of the PSD-based body RMS [Hz] (default 0 20)")
    ap.add_argument("--json", action="store_true",
                    help="print every metric of every run as JSON instead of the table")
    return ap


def _adaptive_h(d: Path) -> float | None:
    try:
        run = json.loads((d / "scenario.json").read_text()).get("run", {})
    except (OSError, ValueError, AttributeError):
        return None
    return float(run["h_min"]) if run.get("adaptive") and run.get("h_min") else None


def _fail(message: str) -> int:
    print(f"suscosim ride: {message}", file=sys.stderr)
    return 2


def main(argv: list[str] | None = None) -> int:
    ap = build_parser()
    try:
        args = ap.parse_args(list(sys.argv[1:] if argv is None else argv))
    except SystemExit as exc:  # argparse already printed its one-line usage error
        return 0 if exc.code == 0 else 2
    lo, hi = args.band
    if not (0.0 <= lo < hi):
        return _fail(f"--band {lo:g} {hi:g}: expected 0 <= LO < HI [Hz]")
    dirs = [Path(r) for r in args.runs]
    for d in dirs:
        if not d.is_dir():
            return _fail(f"{d}: no such run folder")
        if not (d / TABLE).is_file():
            return _fail(f"{d}: no {TABLE} (unfinished run? try 'suscosim export "
                         f"{d / 'journal.msgpack'}')")
    from cosim.table import read_table
    from nodes.recorder.ride_metrics import ride_summary, ride_table

    names = run_names(dirs)
    runs = {}
    for name, d in zip(names, dirs, strict=True):
        try:
            table = read_table(d / TABLE)
        except Exception as exc:  # a corrupt or foreign parquet file: one line, exit 2
            return _fail(f"{d / TABLE}: unreadable ({type(exc).__name__}: {exc})")
        if "t" not in table or len(table["t"]) < 2:
            return _fail(f"{d / TABLE}: no time column 't' with at least two samples")
        h = _adaptive_h(d)
        if h is not None:  # run.h = "auto": the metrics need a uniform time base
            from cosim.table_batches import resampled

            print(f"suscosim ride: {d}: the run's step was adaptive: resampled linearly to "
                  f"h_min = {h:g} s", file=sys.stderr)
            table = next(resampled(iter([{c: np.asarray(v, dtype=float)
                                           for c, v in table.items() if c != "k"}]), h))
        runs[name] = table
    if args.baseline is not None and args.baseline not in runs:
        return _fail(f"--baseline {args.baseline!r}: not one of the runs {names}")
    try:
        if args.json:
            summary = ride_summary(runs, baseline=args.baseline, band_hz=(lo, hi))
            summary["runs"] = [
                {"name": e["name"], "path": str(d), "metrics": e["metrics"],
                 "change_pct": e["change_pct"]} for e, d in zip(summary["runs"], dirs, strict=True)]
            from .runner import strict_json

            text = json.dumps(strict_json(summary), indent=1)
        else:
            text = ride_table(runs, baseline=args.baseline, band_hz=(lo, hi))
    except (ValueError, KeyError) as exc:
        return _fail(str(exc))
    print(text)
    return 0
