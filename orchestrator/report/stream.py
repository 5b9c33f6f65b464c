"""A run folder read for the report (:func:`load_run`: scenario, summary, table or one rebuilt
from the journal, fatigue results, damage map; every piece optional, every problem named), its
table in row batches (memory does not grow with the run): :class:`TableSource`,
:class:`StreamDecimator` (:func:`.plots.decimate`'s points), :class:`StreamWelch`
(``scipy.signal.welch``'s result), :func:`column_stats`.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from cosim.safe_open import read_user_text

BATCH_ROWS = 65_536  # rows read at a time (~0.5 MB a column)
PSD_MAX_NPERSEG = 32_768
"""Largest Welch segment [samples] (n/4 otherwise): 16 s at 2 kHz, 0.06 Hz resolution, well
below the body's ~1 Hz and wheel's ~10 Hz modes; more averages, lower variance (Welch 1967)."""


class TableSource:
    """The columns of a run's table (``names``, ``n_rows``), read in :meth:`batches`."""

    def __init__(self, path: Path | None = None,
                 table: dict[str, np.ndarray] | None = None) -> None:
        self.path, self._table = path, table
        if table is not None:
            self.names = [n for n in table if n != "k"]
            self.n_rows = int(np.asarray(table["t"]).size) if "t" in table else 0
        else:
            import pyarrow.parquet as pq

            assert path is not None
            f = pq.ParquetFile(path)
            self.names = [n for n in f.schema_arrow.names if n != "k"]
            self.n_rows = int(f.metadata.num_rows)

    resample_h: float | None = None  # [s] batches interpolated onto this uniform step

    def set_uniform(self, h: float) -> None:
        """Read the table linearly resampled on a uniform step ``h`` [s] from now on."""
        from cosim.table_batches import uniform_grid_size

        t0 = t1 = None
        for b in self._raw_batches(["t"]):
            t0 = float(b["t"][0]) if t0 is None else t0
            t1 = float(b["t"][-1])
        if t0 is None or t1 is None:
            return
        self.resample_h = h
        self.n_rows = uniform_grid_size(t0, t1, h)

    def batches(self, columns: Sequence[str] | None = None, rows: int = BATCH_ROWS
                ) -> Iterator[dict[str, np.ndarray]]:
        """``{column: values}`` of ``columns`` (default all; ``t`` always), ``rows`` at a time."""
        if self.resample_h is None:
            yield from self._raw_batches(columns, rows)
            return
        from cosim.table_batches import resampled

        yield from resampled(self._raw_batches(columns, rows), self.resample_h)

    def _raw_batches(self, columns: Sequence[str] | None = None, rows: int = BATCH_ROWS
                     ) -> Iterator[dict[str, np.ndarray]]:
        cols = list(dict.fromkeys(["t", *(self.names if columns is None else columns)]))
        cols = [c for c in cols if c in self.names]
        if self._table is not None:
            tab = self._table
            for i in range(0, self.n_rows, rows):
                yield {c: np.asarray(tab[c][i:i + rows], dtype=float) for c in cols}
            return
        from cosim.table_batches import parquet_batches

        assert self.path is not None
        yield from parquet_batches(self.path, cols, rows)

    def read(self, keep: Callable[[str], bool]) -> dict[str, np.ndarray]:
        cols = [c for c in self.names if c == "t" or keep(c)]
        parts: dict[str, list[np.ndarray]] = {c: [] for c in cols}
        for b in self.batches(cols):
            for c in cols:
                parts[c].append(b[c])
        return {c: np.concatenate(v) if v else np.zeros(0) for c, v in parts.items()}

    def whole(self) -> dict[str, np.ndarray]:
        return self.read(lambda _n: True)


class StreamDecimator:
    """:func:`.plots.decimate` of ``n`` samples fed in batches (the same points)."""

    def __init__(self, n: int, n_max: int) -> None:
        self.n, self.n_max = n, n_max
        self.whole = n <= n_max
        self.b = n if self.whole else int(math.ceil(n / (n_max // 2)))
        self.t_parts: list[np.ndarray] = []
        self.x_parts: list[np.ndarray] = []
        self.held_t, self.held_x = np.zeros(0), np.zeros(0)

    def add(self, t: np.ndarray, x: np.ndarray) -> None:
        from .plots import decimate

        self.held_t = np.concatenate([self.held_t, t])
        self.held_x = np.concatenate([self.held_x, x])
        if self.whole:
            return
        cut = self.held_x.size // self.b * self.b
        if cut:
            # whole buckets only: decimate of 2 * (cut / b) points ... buckets of exactly b
            tt, xx = decimate(self.held_t[:cut], self.held_x[:cut], 2 * (cut // self.b),
                              bucket=self.b)
            self.t_parts.append(tt)
            self.x_parts.append(xx)
            self.held_t, self.held_x = self.held_t[cut:], self.held_x[cut:]

    def result(self) -> tuple[np.ndarray, np.ndarray]:
        from .plots import decimate

        if self.whole:
            return self.held_t, self.held_x
        tt, xx = decimate(self.held_t, self.held_x, 2, bucket=self.b) if self.held_x.size \
            else (np.zeros(0), np.zeros(0))  # the last, partial bucket
        return np.concatenate([*self.t_parts, tt]), np.concatenate([*self.x_parts, xx])


def psd_nperseg(n: int) -> int:
    """Welch segment of ``n`` samples: n/4 (256..n), at most :data:`PSD_MAX_NPERSEG`."""
    return int(min(n, max(256, n // 4), PSD_MAX_NPERSEG))


class StreamWelch:
    """``scipy.signal.welch(x, fs, nperseg, detrend="constant")`` of batches (Hann, 50 %)."""

    def __init__(self, fs: float, nperseg: int) -> None:
        from scipy.signal import get_window

        self.fs, self.nperseg = fs, nperseg
        self.step = nperseg - nperseg // 2
        self.win = get_window("hann", nperseg)
        self.scale = 1.0 / (fs * float((self.win * self.win).sum()))
        self.buf = np.zeros(0)
        self.acc = np.zeros(nperseg // 2 + 1)
        self.count = 0

    def add(self, x: np.ndarray) -> None:
        self.buf = np.concatenate([self.buf, np.asarray(x, dtype=float)])
        while self.buf.size >= self.nperseg:
            seg = self.buf[:self.nperseg]
            spec = np.fft.rfft(self.win * (seg - seg.mean()))
            self.acc += (spec.real ** 2 + spec.imag ** 2)
            self.count += 1
            self.buf = self.buf[self.step:]

    def result(self) -> tuple[np.ndarray, np.ndarray]:
        """(f [Hz], P [unit²/Hz]) one-sided; empty arrays before a whole segment."""
        f = np.fft.rfftfreq(self.nperseg, 1.0 / self.fs)
        if self.count == 0:
            return f[:0], f[:0]
        p = self.acc * self.scale / self.count
        if self.nperseg % 2:
            p[1:] *= 2.0
        else:
            p[1:-1] *= 2.0
        return f, p


def column_stats(src: TableSource) -> dict[str, dict[str, float]]:
    """Max, min, peak (signed) and its time, mean, rms, std of every column but ``t``."""
    from cosim.table_writer import _Stats

    stats: dict[str, _Stats] = {}
    for b in src.batches():
        t = b["t"]
        for c, x in b.items():
            if c != "t" and x.size:
                stats.setdefault(c, _Stats()).add(x, t)
    return {c: s.result() for c, s in stats.items()}


class BadInput(Exception):
    """Bad input for the report (exit code 2)."""


@dataclass
class RunData:
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
        return "unknown" if self.summary is None else str(self.summary.get("status", "unknown"))

    @property
    def run_id(self) -> str:
        for src in (self.summary or {}, (self.scenario or {}).get("run", {}) or {}):
            if src.get("run_id") or src.get("id"):
                return str(src.get("run_id") or src.get("id"))
        return self.path.name

    @cached_property
    def table(self) -> dict[str, np.ndarray] | None:
        """Every column whole, read on first use (the sweep pages' short runs)."""
        return None if self.source is None else self.source.whole()

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
    pngs = (d / "fatigue" / "damage_map.png", d / "fatigue" / "sn_plot.png")
    r.damage_map, r.sn_plot = (p if p.is_file() else None for p in pngs)
    return r
