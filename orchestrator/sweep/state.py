"""The state of a point's run folder (done, fatigue missing, to do) and a running run's
progress read from the tail of its journal."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from .spec import Point


def _read_json(path: Path) -> Any:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def point_state(p: Point, run_dir: Path, fatigue: bool) -> str:
    """``done``, ``fatigue`` (run ok, fatigue missing) or ``todo``."""
    meta = _read_json(run_dir / "point.json")
    summary = _read_json(run_dir / "summary.json")
    if not isinstance(meta, dict) or meta.get("fingerprint") != p.fingerprint or \
            not isinstance(summary, dict) or summary.get("status") != "ok":
        return "todo"
    if fatigue and not isinstance(_read_json(run_dir / "fatigue" / "summary.json"), dict):
        return "fatigue"
    return "done"


def journal_step(path: Path, tail_bytes: int = 32768) -> int | None:
    """The step index of the last intact record of a run journal that carries one (cheap:
    reads its tail with the journal reader every command uses), or None."""
    import msgpack

    from nodes.recorder.journal import read_journal

    try:
        records = read_journal(path, tail_bytes=tail_bytes).records
    except (OSError, ValueError):
        return None
    for _channel, raw in reversed(records):
        try:
            msg = msgpack.unpackb(raw, raw=False)
        except Exception:
            continue
        if isinstance(msg, dict) and isinstance(msg.get("k"), int):
            return int(msg["k"])
    return None

