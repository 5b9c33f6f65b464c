"""The state of a point's run folder (done, fatigue missing, to do) and a running run's
progress read from the tail of its journal."""

from __future__ import annotations

from pathlib import Path

from cosim.run_folder import read_json

from .spec import Point


def point_state(p: Point, run_dir: Path, fatigue: bool) -> str:
    """``done``, ``fatigue`` (run ok, fatigue missing) or ``todo``."""
    meta = read_json(run_dir / "point.json")
    summary = read_json(run_dir / "summary.json")
    if not isinstance(meta, dict) or meta.get("fingerprint") != p.fingerprint or \
            not isinstance(summary, dict) or summary.get("status") != "ok":
        return "todo"
    if fatigue and not isinstance(read_json(run_dir / "fatigue" / "summary.json"), dict):
        return "fatigue"
    return "done"
