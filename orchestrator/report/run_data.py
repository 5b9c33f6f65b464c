"""What a run folder holds, read for the report (scenario, summary, table or one rebuilt from
the journal, fatigue results, damage map): every piece optional, every problem named."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cosim.safe_open import read_user_text

from .stream import TableSource


class BadInput(Exception):
    """Bad input for the report (exit code 2)."""


@dataclass
class RunData:
    """What a run folder holds (every piece optional) and what was wrong with it."""

    path: Path
    scenario: dict | None = None
    summary: dict | None = None
    source: TableSource | None = None  # the table, read in batches
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

    @property
    def table(self) -> dict[str, np.ndarray] | None:
        """Every column whole, read on first use (the sweep pages' short runs)."""
        if self.source is None:
            return None
        if self._whole is None:
            self._whole = self.source.whole()
        return self._whole

    _whole: dict[str, np.ndarray] | None = field(default=None, repr=False)

    def has_arm(self) -> bool:
        return self.source is not None and any(c.startswith("plant/arm/")
                                               for c in self.source.names)


def _read_json(path: Path, problems: list[str]) -> Any:
    if not path.is_file():
        return None
    try:
        return json.loads(read_user_text(path, "report", inside=path.parent))
    except (OSError, ValueError) as exc:  # InputFileError, UnicodeDecodeError, JSON
        problems.append(f"{path.name}: unreadable ({exc})")
        return None


def is_run_dir(d: Path) -> bool:
    return any((d / n).is_file() for n in ("scenario.json", "summary.json", "journal.msgpack",
                                          "table.parquet", "table.csv"))


def load_run(d: Path) -> RunData:
    """Read every piece of a run folder that exists; never raises for a bad piece."""
    r = RunData(path=d)
    sc = _read_json(d / "scenario.json", r.problems)
    r.scenario = sc if isinstance(sc, dict) else None
    sm = _read_json(d / "summary.json", r.problems)
    r.summary = sm if isinstance(sm, dict) else None
    for name in ("table.parquet", "table.csv"):
        p = d / name
        if p.is_file() and r.source is None:
            try:
                if name == "table.parquet":
                    src = TableSource(path=p)  # its schema and row count only
                else:
                    from cosim.table import read_table

                    src = TableSource(table={k: np.asarray(v, dtype=float)
                                             for k, v in read_table(p).items()})
            except Exception as exc:  # a torn or foreign file: say so, try the next source
                r.problems.append(f"{name}: unreadable ({type(exc).__name__}: {exc})")
                continue
            r.source, r.table_note = src, name
    if r.source is None and (d / "journal.msgpack").is_file():
        try:
            from cosim.journal import read_journal
            from cosim.table_writer import journal_table

            contents = read_journal(d / "journal.msgpack")
            tab, _bad = journal_table(contents.records)
            extra = f"; journal: {contents.problem}" if contents.problem else ""
            if len(tab["t"]):
                r.source = TableSource(table={k: np.asarray(v, dtype=float)
                                              for k, v in tab.items()})
                r.table_note = "rebuilt from journal.msgpack (the run left no table)" + extra
            else:
                r.table_note = "journal.msgpack holds no complete step" + extra
        except Exception as exc:
            r.problems.append(f"journal.msgpack: unreadable ({type(exc).__name__}: {exc})")
    run_cfg = (r.scenario or {}).get("run") or {}
    if r.source is not None and run_cfg.get("adaptive") and "t" in r.source.names:
        h = float(run_cfg.get("h_min") or run_cfg["h"])  # an adaptive step: a uniform grid
        r.source.set_uniform(h)
        r.table_note += (f"; the run's step was adaptive (run.h = \"auto\"): resampled "
                         f"linearly to h_min = {h:g} s for the plots, PSDs and ride metrics")
    if r.source is not None and ("t" not in r.source.names or r.source.n_rows < 2):
        r.problems.append(f"{r.table_note}: fewer than 2 samples")
        r.source = None
    fs = _read_json(d / "fatigue" / "summary.json", r.problems)
    r.fatigue = fs if isinstance(fs, dict) else None
    if (d / "fatigue" / "damage_map.png").is_file():
        r.damage_map = d / "fatigue" / "damage_map.png"
    if (d / "fatigue" / "sn_plot.png").is_file():
        r.sn_plot = d / "fatigue" / "sn_plot.png"
    return r
