"""Batch fatigue of a load history in row batches: memory that does not grow with the run.

``suscosim fatigue RUN_DIR`` reads ``table.parquet`` (or ``table.csv``) in batches of
:data:`BATCH_ROWS` rows (a load file is one batch) and feeds the live node's block engine
(:class:`.worker.LiveFatigue`, blocks of ``fatigue.block_samples`` from the first sample:
:func:`.worker.analyse`'s damage bit for bit). Four passes:

1. **check** (:func:`scan`): times finite and strictly increasing, every load sample
   plausible (:func:`.load_file.bad_sample`, the index counted from the table's first row),
   each channel's peak, and its rainflow cycles streamed (count, largest range, mean
   extremes: its matrix's axes; the pseudo-damage terms summed);
2. **damage**: the primary analysis and every S-N method of :func:`.outputs.method_table`
   (an engine each, fed the same batches); each channel's range-mean matrix on pass 1's axes;
3. **critical node**: its six stress components and equivalent stress by superposition,
   written to ``critical_stress.csv`` row by row, its cycles into the S-N plot's spectrum
   (:class:`.outputs.SnSpectrum`) and its matrix's axes;
4. **critical node's matrix**: its equivalent stress again (one node: cheap), binned.

Memory: a batch of the arm's columns (~16 x 65 536 rows x 8 B = 8 MB), the engines' per-node
state, the residues and the fixed-size spectrum and matrices. The whole-history outputs are the
test oracle (tests/fatigue/whole_outputs.py): the same bits, except a channel's pseudo-damage,
summed batch by batch instead of one pairwise ``np.sum`` over all cycles (a few 1e-16
relative: unavoidable without holding every cycle, which grows with the run).
"""

from __future__ import annotations

import csv
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from cosim.errors import InputFileError

from .config import FatigueConfig
from .lib.counting import Cycles, StreamingRainflow
from .lib.equivalent_stress import equivalent
from .lib.influence_set import short_channel
from .lib.pseudo_damage import (
    K_REF,
    N_REF,
    ChannelPseudoDamage,
    equivalent_range,
    matrix_rows,
    rainflow_matrix,
    reference_range,
)
from .lib.superposition import stress_history
from .load_file import bad_sample, bad_samples
from .more_parts import column_names
from .outputs import (
    SnSpectrum,
    method_table,
    methods_summary,
    sn_plot,
    write_pseudo_damage,
    write_vtu,
)
from .worker import FatigueResult, LiveFatigue, case_matrix, load_influence

BATCH_ROWS = 65_536
"""Rows of the table read at a time (a multiple of any ``block_samples`` it is rechunked to)."""
N_BINS = 32
"""Bins of a range-mean rainflow matrix, as :func:`.pseudo_damage.rainflow_matrix`."""

Batches = Callable[[], Iterator[tuple[np.ndarray, dict[str, np.ndarray]]]]
"""A function that starts a pass: an iterator of (t, {load column: values}) batches."""


def table_source(run_dir: Path) -> Path:
    """``table.parquet``, else ``table.csv`` of a run folder (InputFileError if neither)."""
    src = next((p for p in (run_dir / "table.parquet", run_dir / "table.csv") if p.is_file()),
               None)
    if src is None:
        raise InputFileError(str(run_dir), "no table.parquet or table.csv in the run folder")
    return src


def table_batches(src: Path, rows: int = BATCH_ROWS, channel: str = "arm",
                  cases: Sequence[str] = ()) -> Batches:
    """Batches of ``t`` and the ``plant/<channel>/...`` columns of a run's table (a four-corner
    run's ``arm_<corner>``: that corner's loads), named as a part's ``cases`` name them
    (:func:`.more_parts.column_names`; any channel but the upper arm's, a corner's too, is
    the lower arm's ``plant/arm/...``).

    Parquet: a row group at a time (:func:`cosim.table_batches.parquet_batches`). CSV (a
    run that left no Parquet table): read whole by :func:`cosim.table.read_table`, then cut
    (bounded only for Parquet)."""
    prefix = f"plant/{channel}/"

    def named(cols: list[str]) -> list[str]:
        return column_names(channel, [c[len(prefix):] for c in cols], list(cases))

    if src.suffix == ".parquet":
        import pyarrow.parquet as pq

        try:
            names = pq.ParquetFile(src).schema_arrow.names
        except Exception as exc:  # pyarrow raises several types for a bad file
            raise InputFileError(str(src), f"not a readable Parquet file ({exc})") from None
        if "t" not in names:
            raise InputFileError(str(src), "no column 't'")
        cols = [n for n in names if n.startswith(prefix)]
        keys = named(cols)

        def parquet() -> Iterator[tuple[np.ndarray, dict[str, np.ndarray]]]:
            from cosim.table_batches import parquet_batches

            try:
                for b in parquet_batches(src, ["t", *cols], rows):
                    yield b["t"], {k: b[c] for k, c in zip(keys, cols, strict=True)}
            except (OSError, ValueError) as exc:
                raise InputFileError(str(src), f"not a readable Parquet file ({exc})") from None
        return parquet

    from cosim.table import read_table

    whole = {n: np.asarray(v, dtype=float)
             for n, v in read_table(src, keep=lambda n: n.startswith(prefix)).items()}
    whole.pop("k", None)
    if "t" not in whole:
        raise InputFileError(str(src), "no column 't'", 1)
    t_all = whole.pop("t")
    data = dict(zip(named(list(whole)), whole.values(), strict=True))

    def from_csv() -> Iterator[tuple[np.ndarray, dict[str, np.ndarray]]]:
        for i in range(0, t_all.size, rows):
            yield t_all[i:i + rows], {c: v[i:i + rows] for c, v in data.items()}
    return from_csv


@dataclass
class _Channel:
    """Pass 1's view of one load channel: its first bad sample, cycles and their axes."""

    first_bad: tuple[int, float, float] | None = None  # (sample, value, t)
    n_bad: int = 0
    peak_abs: float = 0.0
    rf: StreamingRainflow = field(default_factory=lambda: StreamingRainflow(1))
    cycles: float = 0.0
    max_range: float = 0.0
    m_lo: float = np.inf
    m_hi: float = -np.inf
    pd_sum: float = 0.0
    n_cyc: int = 0


@dataclass
class Scan:
    """What pass 1 found: sample count, the times needed for the duration, per channel."""

    n: int = 0
    t0: float = np.nan
    t1: float = np.nan
    t_last: float = np.nan
    channels: dict[str, _Channel] = field(default_factory=dict)

    @property
    def duration_s(self) -> float:
        """As :func:`.worker.analyse`: t[-1] - t[0] + (t[1] - t[0]) [s]."""
        return float(self.t_last - self.t0 + (self.t1 - self.t0)) if self.n > 1 else 0.0


def _cycles_done(ch: _Channel, cyc: Cycles) -> None:
    """Fold closed cycles into a channel's totals (pass 1)."""
    if len(cyc) == 0:
        return
    r, m = cyc.range, cyc.mean
    ch.n_cyc += len(cyc)
    ch.cycles += float(cyc.count.sum())
    ch.max_range = max(ch.max_range, float(r.max()))
    ch.m_lo, ch.m_hi = min(ch.m_lo, float(m.min())), max(ch.m_hi, float(m.max()))
    ch.pd_sum += float(np.sum(cyc.count * (r / reference_range("")) ** K_REF))  # 1 kN (m)


def scan(batches: Batches, source: str, residue: str, loads_source: str | None = None) -> Scan:
    """Pass 1 (module docstring): raise InputFileError for a bad time (naming ``source``, the
    table file) or load sample (naming ``loads_source``), the first one, in the words of
    ``run_dir.read_table`` and :func:`.load_file.check_loads`."""
    where = loads_source or source
    s = Scan()
    t_prev = -np.inf
    for t, loads in batches():
        if not s.channels:
            s.channels = {c: _Channel() for c in loads}
        if t.size and (not np.all(np.isfinite(t)) or t[0] <= t_prev
                       or np.any(np.diff(t) <= 0)):
            raise InputFileError(source, "column 't' is not strictly increasing")
        if t.size:
            if s.n == 0:
                s.t0 = float(t[0])
            if s.n <= 1 < s.n + t.size:
                s.t1 = float(t[1 - s.n])
            s.t_last = t_prev = float(t[-1])
        for name, v in loads.items():
            ch = s.channels[name]
            bad = bad_samples(name, v)
            if bad.size:
                if ch.first_bad is None:
                    i = int(bad[0])
                    ch.first_bad = (s.n + i, float(v[i]), float(t[i]))
                ch.n_bad += bad.size
            elif ch.first_bad is None and v.size:
                ch.peak_abs = max(ch.peak_abs, float(np.max(np.abs(v))))
                _cycles_done(ch, ch.rf.feed(v.reshape(-1, 1)))
        s.n += t.size
    if s.n < 2:
        raise InputFileError(source, "fewer than 2 samples")
    for name, ch in s.channels.items():
        if ch.first_bad is not None:
            i, x, when = ch.first_bad
            raise InputFileError(where, bad_sample(name, i, x, when, ch.n_bad))
        _cycles_done(ch, ch.rf.residue_cycles(residue))
    return s


def _rechunk(batches: Batches, block: int
             ) -> Iterator[tuple[np.ndarray, dict[str, np.ndarray]]]:
    """The batches re-cut so that every piece but the last is a multiple of ``block`` rows
    (the engine cuts its blocks from each piece's first sample: the same blocks as whole)."""
    held_t: list[np.ndarray] = []
    held: list[dict[str, np.ndarray]] = []
    n_held = 0
    for t, loads in batches():
        held_t.append(t)
        held.append(loads)
        n_held += t.size
        cut = n_held // block * block
        if cut == 0:
            continue
        tt = np.concatenate(held_t)
        ll = {c: np.concatenate([h[c] for h in held]) for c in loads}
        yield tt[:cut], {c: v[:cut] for c, v in ll.items()}
        held_t, held = [tt[cut:]], [{c: v[cut:] for c, v in ll.items()}]
        n_held -= cut
    if n_held:
        tt = np.concatenate(held_t)
        yield tt, {c: np.concatenate([h[c] for h in held]) for c in held[0]}


class _Matrix:
    """A range-mean rainflow matrix of one history binned as its cycles close, on the axes
    its pass-1 (or pass-3) totals ``ch`` give, as :func:`rainflow_matrix` sets them."""

    def __init__(self, ch: _Channel, residue: str) -> None:
        self.axes = None if ch.n_cyc == 0 else (
            ch.max_range or 1.0, *((ch.m_lo, ch.m_hi) if ch.m_hi > ch.m_lo
                              else (ch.m_lo - 0.5, ch.m_hi + 0.5)))
        self.residue = residue
        self.rf = StreamingRainflow(1)
        self.H: np.ndarray | None = None
        self.edges: tuple[list, list] = ([], [])

    def feed(self, v: np.ndarray) -> None:
        if self.axes is not None:
            self._add(self.rf.feed(v.reshape(-1, 1)))

    def _add(self, cyc: Cycles) -> None:
        if len(cyc) and self.axes is not None:
            r_hi, m_lo, m_hi = self.axes
            h, re, me = np.histogram2d(cyc.range, cyc.mean, bins=N_BINS,
                                       range=[[0.0, r_hi], [m_lo, m_hi]], weights=cyc.count)
            self.H = h if self.H is None else self.H + h
            self.edges = (re.tolist(), me.tolist())

    def result(self) -> dict:
        """The matrix (:func:`rainflow_matrix`'s dict), the residue's cycles added."""
        if self.axes is None:
            return rainflow_matrix(Cycles.empty())
        self._add(self.rf.residue_cycles(self.residue))
        assert self.H is not None
        return {"range_edges": self.edges[0], "mean_edges": self.edges[1],
                "counts": self.H.tolist()}


def analyse_streamed(batches: Batches, cfg: FatigueConfig, L: float, s: Scan,
                     say: Callable[[str], None]
                     ) -> tuple[FatigueResult, dict | None, dict[str, dict]]:
    """Pass 2: (primary result, ``sn_methods`` (:func:`.outputs.methods_summary`), every load
    channel's :func:`rainflow_matrix` dict)."""
    names = list(s.channels)
    primary = LiveFatigue(cfg, names, L)
    table, left = method_table(cfg)
    others = {(m, P): LiveFatigue(c, names, L) for m, P, c in table if c != cfg}
    mats = {c: _Matrix(ch, cfg.residue) for c, ch in s.channels.items()}
    say(f"fatigue: {s.n} samples x {len(names)} channels, primary S-N curve"
        + (f" and {len(others)} more" if others else "") + " (streamed)")
    for t, loads in _rechunk(batches, max(1, cfg.block_samples)):
        primary.update(t, loads)
        for lf in others.values():
            lf.update(t, loads)
        for c, v in loads.items():
            mats[c].feed(v)
    matrices = {c: m.result() for c, m in mats.items()}
    result = _finish(primary, s)
    methods = None
    if table:  # the primary's own entry is the primary (the same config: the same result)
        methods = methods_summary([(m, P, c, result if c == cfg else _finish(others[(m, P)], s))
                                   for m, P, c in table], left)
    return result, methods, matrices


def _finish(lf: LiveFatigue, s: Scan) -> FatigueResult:
    r = lf.result()
    r.duration_s = s.duration_s  # analyse's t[-1] - t[0] + (t[1] - t[0]), not the last dt
    r.source = "batch"
    return r


def pseudo_damage_of(s: Scan, n_ref: float = N_REF) -> list[ChannelPseudoDamage]:
    """Every load channel's pseudo-damage from pass 1's sums (module docstring)."""
    out = []
    for name, ch in s.channels.items():
        ref = reference_range(name)
        d = ch.pd_sum / n_ref if ch.n_cyc else 0.0
        out.append(ChannelPseudoDamage(
            channel=name, cycles=ch.cycles, max_range=ch.max_range, pseudo_damage=d,
            equivalent_range=equivalent_range(d, K_REF, ref), k=K_REF, ref_range=ref,
            n_ref=n_ref))
    return out


def outputs_streamed(batches: Batches, cfg: FatigueConfig, s: Scan, result: FatigueResult,
                     methods: dict | None, matrices: dict[str, dict],
                     say: Callable[[str], None]) -> tuple[Callable[[Path], None], dict]:
    """(writer of the batch output files (:mod:`.outputs`) into a folder, summary keys);
    the writer runs pass 3 (the critical node's history)."""
    pd = pseudo_damage_of(s)
    extra = {"sn_methods": methods,
             "pseudo_damage": {"k": K_REF, "channels": [p.as_dict() for p in pd]},
             "outputs": ["critical_stress.csv", "rainflow_matrix.csv", "pseudo_damage.csv",
                         "sn_plot.png", "sn_plot.json", "damage.vtu"]}
    inf = load_influence(cfg)
    cases = list(inf.case_names)
    coef = inf.coefficients[:, result.critical_node:result.critical_node + 1, :]

    def eq_batches() -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """(t, the six stress components, the equivalent stress) at the critical node [Pa],
        a batch at a time."""
        for t, loads in batches():
            st = stress_history(case_matrix(cases, loads), coef)
            yield t, st[:, 0, :], equivalent(st, cfg.equivalent)[:, 0]

    def write(folder: Path) -> None:
        say("fatigue: critical-node history, rainflow matrices, pseudo-damage")
        # pass 3: the history written, its cycles counted (the S-N spectrum, the matrix axes)
        spectrum = SnSpectrum(cfg)
        crit = _Channel()
        rf = StreamingRainflow(1)
        with open(folder / "critical_stress.csv", "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["t_s", "sxx_pa", "syy_pa", "szz_pa", "sxy_pa", "syz_pa", "szx_pa",
                        f"eq_{cfg.equivalent}_pa"])
            for t, s6, eq in eq_batches():
                for i in range(t.size):
                    w.writerow([f"{t[i]:.9g}", *(f"{v:.6e}" for v in s6[i]), f"{eq[i]:.6e}"])
                cyc = rf.feed(eq.reshape(-1, 1))
                _cycles_done(crit, cyc)
                spectrum.add(cyc)
        cyc = rf.residue_cycles(cfg.residue)
        _cycles_done(crit, cyc)
        spectrum.add(cyc)
        # pass 4: the critical node's range-mean matrix on the axes pass 3 found
        node = _Matrix(crit, cfg.residue)
        for _t, _s6, eq in (eq_batches() if node.axes is not None else ()):
            node.feed(eq)
        node_matrix = node.result()
        with open(folder / "rainflow_matrix.csv", "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["series", "unit", "range_lo", "range_hi", "mean_lo", "mean_hi",
                        "cycles"])
            w.writerows(matrix_rows(f"node_{result.critical_node_id}", "Pa", node_matrix))
            for name, mat in matrices.items():
                unit = "N m" if short_channel(name).endswith("_mx") else "N"
                w.writerows(matrix_rows(name, unit, mat))
        write_pseudo_damage(folder / "pseudo_damage.csv", pd)
        sn_plot(folder / "sn_plot.png", cfg, spectrum, result, methods)
        write_vtu(folder / "damage.vtu", result)

    return write, extra
