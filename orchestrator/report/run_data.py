"""What a run folder holds, read for the report: scenario, summary, table (or one rebuilt
from the journal), fatigue results and damage map; every piece optional, every problem named.

Reads files only (no import of the sweep or the recorder node's internals beyond its table
and journal readers)."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np


class BadInput(Exception):
    """Bad input for the report (exit code 2)."""


@dataclass
class RunData:
    """What a run folder holds (every piece optional) and what was wrong with it."""

    path: Path
    scenario: dict | None = None
    summary: dict | None = None
    table: dict[str, np.ndarray] | None = None
    table_note: str = ""
    fatigue: dict | None = None
    damage_map: Path | None = None
    sn_plot: Path | None = None
    problems: list[str] = field(default_factory=list)

    @property
    def status(self) -> str:
        if self.summary is None:
            return "unknown"
        return str(self.summary.get("status", "unknown"))

    @property
    def run_id(self) -> str:
        for src in (self.summary or {}, (self.scenario or {}).get("run", {}) or {}):
            if src.get("run_id") or src.get("id"):
                return str(src.get("run_id") or src.get("id"))
        return self.path.name

    def has_arm(self) -> bool:
        return self.table is not None and any(c.startswith("plant/arm/") for c in self.table)


def _read_json(path: Path, problems: list[str]) -> Any:
    if not path.is_file():
        return None
    try:
        return json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        problems.append(f"{path.name}: unreadable ({exc})")
        return None


def is_run_dir(d: Path) -> bool:
    return any((d / n).is_file() for n in ("scenario.json", "summary.json", "journal.msgpack",
                                          "table.parquet", "table.csv"))


def is_sweep_dir(d: Path) -> bool:
    return (d / "sweep.json").is_file()


def load_run(d: Path) -> RunData:
    """Read every piece of a run folder that exists; never raises for a bad piece."""
    from cosim.table import read_table

    r = RunData(path=d)
    sc = _read_json(d / "scenario.json", r.problems)
    r.scenario = sc if isinstance(sc, dict) else None
    sm = _read_json(d / "summary.json", r.problems)
    r.summary = sm if isinstance(sm, dict) else None
    for name in ("table.parquet", "table.csv"):
        p = d / name
        if p.is_file() and r.table is None:
            try:
                tab = read_table(p)
            except Exception as exc:  # a torn or foreign file: say so, try the next source
                r.problems.append(f"{name}: unreadable ({type(exc).__name__}: {exc})")
                continue
            r.table, r.table_note = tab, name
    if r.table is None and (d / "journal.msgpack").is_file():
        try:
            from cosim.journal import read_journal
            from cosim.table import build_table

            contents = read_journal(d / "journal.msgpack")
            tab, _bad = build_table(contents.records)
            extra = f"; journal: {contents.problem}" if contents.problem else ""
            if len(tab["t"]):
                r.table = tab
                r.table_note = "rebuilt from journal.msgpack (the run left no table)" + extra
            else:
                r.table_note = "journal.msgpack holds no complete step" + extra
        except Exception as exc:
            r.problems.append(f"journal.msgpack: unreadable ({type(exc).__name__}: {exc})")
    if r.table is not None:
        r.table = {k: np.asarray(v, dtype=float) for k, v in r.table.items() if k != "k"}
        if "t" not in r.table or r.table["t"].size < 2:
            r.problems.append(f"{r.table_note}: fewer than 2 samples")
            r.table = None
    fs = _read_json(d / "fatigue" / "summary.json", r.problems)
    r.fatigue = fs if isinstance(fs, dict) else None
    if (d / "fatigue" / "damage_map.png").is_file():
        r.damage_map = d / "fatigue" / "damage_map.png"
    if (d / "fatigue" / "sn_plot.png").is_file():
        r.sn_plot = d / "fatigue" / "sn_plot.png"
    return r
