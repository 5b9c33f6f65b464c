"""A run's table written as its rows complete, in bounded memory.

The table of a run or a journal (:func:`table_of_journal`, :func:`journal_table`): ``k``,
``t`` [s], then ``<node>/<channel>/<field>`` (a list field becomes ``<field>[i]``), channels
sorted by name and each channel's fields sorted; a row is a step every channel delivered (a
step some channel never gave is no row), ``t`` that of the channel heard first; the first
message of a step counts. :class:`TableWriter` holds only the steps not yet complete and
writes a row once every channel has given its step, to ``table.csv`` and ``table.parquet``
beside their place until :meth:`TableWriter.close` renames them over it. A step completed
after a later row was written (never in a run) is left out, counted in ``late``.

A channel's layout (its fields, each a number or a list of one length) is fixed by its first
message, or given (``layout``: what :func:`journal_layout` finds by majority in a journal);
a message of another layout is left out, with the reason.
"""

from __future__ import annotations

import csv
import heapq
import io
import math
import os
import threading
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .errors import WireError
from .table_batches import arrow_column
from .wire import decode

Layout = tuple[tuple[str, int | None], ...]
"""A channel's fields in table order: (name, None for a number or n for a list of n)."""

CHUNK_ROWS = 4096  # rows turned into arrays (and CSV lines) at a time
GROUP_ROWS = 16384  # rows per Parquet row group (~6 MB of a 43-column corner at most)


def layout_of(d: Mapping[str, Any]) -> Layout:
    """The layout a message's fields give."""
    return tuple((f, len(v) if type(v) is list else None) for f, v in sorted(d.items()))


class _Stats:
    """Running max/min/peak/mean/rms/std of one column, combined chunk by chunk (Chan et
    al.'s pairwise update for the variance): equal to numpy's whole-array values to the
    last bits of the mean, rms and std (a sum in another order), the extremes exactly; a
    NaN in the column makes every value NaN as numpy's (a law's ``F_demand`` may be NaN)."""

    __slots__ = ("n", "mx", "mn", "peak", "t_peak", "mean", "m2", "sq")

    def __init__(self) -> None:
        self.n, self.mx, self.mn, self.peak, self.t_peak = 0, -math.inf, math.inf, 0.0, 0.0
        self.mean, self.m2, self.sq = 0.0, 0.0, 0.0

    def add(self, x: np.ndarray, t: np.ndarray) -> None:
        m = x.size
        i = int(np.argmax(np.abs(x)))
        if self.n == 0 or abs(x[i]) > abs(self.peak) or math.isnan(x[i]):
            self.peak, self.t_peak = float(x[i]), float(t[i])
        self.mx = float(np.maximum(self.mx, x.max()))  # NaN-propagating, as x.max()
        self.mn = float(np.minimum(self.mn, x.min()))
        mean_b = float(x.mean())
        m2_b = float(np.sum((x - mean_b) ** 2))
        n = self.n + m
        delta = mean_b - self.mean
        self.mean += delta * m / n
        self.m2 += m2_b + delta * delta * self.n * m / n
        self.sq += float(np.sum(x * x))
        self.n = n

    def result(self) -> dict[str, float]:
        return {"max": self.mx, "min": self.mn, "peak": self.peak, "t_peak": self.t_peak,
                "mean": self.mean, "rms": math.sqrt(self.sq / self.n),
                "std": math.sqrt(self.m2 / self.n if not self.m2 < 0.0 else 0.0)}


class TableWriter:
    """Rows written as they complete (module docstring). ``folder`` None: nothing on disk
    (with ``keep`` the columns in memory); ``first``: the channels in the order first heard,
    when known before; ``strict``: a message has exactly its channel's fields (else at least)."""

    def __init__(self, channels: Iterable[str], folder: str | Path | None,
                 layout: Mapping[str, Layout] | None = None, first: Iterable[str] = (),
                 chunk_rows: int | None = None, group_rows: int | None = None,
                 strict: bool = True, keep: bool = False) -> None:
        self.channels = sorted(set(channels))
        if not self.channels:
            raise ValueError("a table needs at least one channel")
        self._index = {c: i for i, c in enumerate(self.channels)}
        self.layout: dict[str, Layout] = dict(layout or {})
        self._rank: dict[str, int] = {c: i for i, c in enumerate(first)}
        self.folder = None if folder is None else Path(folder)
        self.chunk_rows = CHUNK_ROWS if chunk_rows is None else chunk_rows
        self.strict, self.keep = strict, keep
        self.group_rows = GROUP_ROWS if group_rows is None else group_rows
        self._pending: dict[int, list[Any]] = {}  # k -> [t, rank of t, n, vals per channel]
        self._heap: list[int] = []
        self._rows: list[list[Any]] = []
        self._group: list[dict[str, np.ndarray]] = []
        self._group_n = 0
        self.rows = 0
        self.last_k = -1
        self.late = 0
        self.columns: list[str] | None = None
        self._stats: list[_Stats] = []
        self._csv: Any = None
        self._pq: Any = None
        self._tmp: dict[str, Path] = {}
        self._tag = f"{os.getpid()}.{threading.get_ident()}"

    # ---- taking messages ------------------------------------------------------------------
    def add(self, channel: str, k: int, t: float, d: Mapping[str, Any]) -> str | None:
        """Take ``channel``'s message of step ``k``: None when it is valid for the table, else
        why it is left out (not a channel of the table, another layout, a step already
        given); one of a step at or before the last row written is counted in :attr:`late`."""
        ci = self._index.get(channel)
        if ci is None:
            return f"channel {channel} is not one of the table's"
        if channel not in self._rank:
            self._rank[channel] = len(self._rank)
        lay = self.layout.get(channel)
        if lay is None:
            self.layout[channel] = lay = layout_of(d)
        elif not _fits(d, lay, self.strict):
            return (f"step {k}: fields {_text(layout_of(d))} where the channel has "
                    f"{_text(lay)}")
        if k <= self.last_k:  # its row was written, or a later one was: it cannot be one
            self.late += 1  # taken all the same (the journal keeps it), counted
            return None
        row = self._pending.get(k)
        if row is None:
            row = self._pending[k] = [t, self._rank[channel], 0] + [None] * len(self.channels)
            heapq.heappush(self._heap, k)
        if not self._fill(k, ci, channel, t, d, row):
            return f"step {k} again"
        return None

    def _fill(self, k: int, ci: int, channel: str, t: float, d: Mapping[str, Any],
              row: list[Any] | None = None) -> bool:
        row = self._pending[k] if row is None else row
        if row[3 + ci] is not None:
            return False
        vals: list[Any] = []
        for f, n in self.layout[channel]:
            if n is None:
                vals.append(d[f])
            else:
                vals.extend(d[f])
        row[3 + ci] = vals
        rank = self._rank[channel]
        if rank < row[1]:
            row[0], row[1] = t, rank
        row[2] += 1
        if row[2] == len(self.channels) and k > self.last_k:
            self._emit(k, row)
        return True

    def _emit(self, k: int, row: list[Any]) -> None:
        heap, pending = self._heap, self._pending
        while heap and heap[0] <= k:  # steps before k can no longer become rows
            del pending[heapq.heappop(heap)]
        flat = [k, row[0]]
        for vals in row[3:]:
            flat += vals
        self._rows.append(flat)
        self.rows += 1
        self.last_k = k
        if len(self._rows) >= self.chunk_rows:
            self._chunk()

    @property
    def held(self) -> int:
        """Steps held, not yet complete."""
        return len(self._pending)

    # ---- writing --------------------------------------------------------------------------
    def _names(self) -> list[str]:
        cols = ["k", "t"]
        for c in self.channels:
            for f, n in self.layout[c]:
                cols += [f"{c}/{f}"] if n is None else [f"{c}/{f}[{i}]" for i in range(n)]
        return cols

    def _open(self) -> None:
        self.columns = self._names()
        self._stats = [_Stats() for _ in self.columns[2:]]
        if self.folder is None:
            return
        for kind in ("csv", "parquet"):
            self._tmp[kind] = self.folder / f".table.{kind}.{self._tag}.tmp"
        head = io.StringIO(newline="")
        csv.writer(head).writerow(self.columns)
        self._csv = open(self._tmp["csv"], "w", newline="")
        self._csv.write(head.getvalue())

    def _chunk(self) -> None:
        rows, self._rows = self._rows, []
        if not rows:
            return
        if self.columns is None:
            self._open()
        ks = np.asarray([r[0] for r in rows], dtype=np.int64)
        vals = np.asarray([r[1:] for r in rows], dtype=float)
        ts = vals[:, 0]
        for j, st in enumerate(self._stats):
            st.add(vals[:, j + 1], ts)
        if self.folder is None and not self.keep:
            return
        assert self.columns is not None
        cols = {"k": ks}
        for j, name in enumerate(self.columns[1:]):
            cols[name] = np.ascontiguousarray(vals[:, j])
        self._group.append(cols)
        if self.folder is None:
            return
        self._csv.writelines(f"{k}," + ",".join(map(str, r)) + "\r\n"
                             for k, r in zip(ks.tolist(), vals.tolist(), strict=True))
        self._group_n += len(rows)
        if self._group_n >= self.group_rows:
            self._write_group()

    def _write_group(self) -> None:
        if not self._group:
            return
        import pyarrow as pa
        import pyarrow.parquet as pq

        assert self.columns is not None
        group, self._group, self._group_n = self._group, [], 0
        tbl = pa.table({c: arrow_column(np.concatenate([g[c] for g in group]))
                        for c in self.columns})
        if self._pq is None:
            self._pq = pq.ParquetWriter(self._tmp["parquet"], tbl.schema)
        self._pq.write_table(tbl)

    def flush(self) -> None:
        """Write the complete rows held (a chunk of fewer rows than usual)."""
        self._chunk()
        if self._csv is not None:
            self._csv.flush()

    def close(self, stem: str | None = "table") -> dict[str, str]:
        """Put the files in place as ``<stem>.*`` (None: remove them); their paths."""
        self._chunk()
        self._pending.clear()
        self._heap.clear()
        if self.folder is None or self.columns is None:
            return {}
        self._write_group()
        if self._pq is not None:
            self._pq.close()
            self._pq = None
        self._csv.close()
        paths: dict[str, str] = {}
        try:
            if stem is not None and self.rows:
                for kind, tmp in self._tmp.items():
                    path = self.folder / f"{stem}.{kind}"
                    os.replace(tmp, path)
                    paths[kind] = str(path)
        finally:
            for tmp in self._tmp.values():
                tmp.unlink(missing_ok=True)
        return paths

    def abandon(self) -> None:
        """Close and remove the files aside (after an error writing them; a second error while
        closing, e.g. a full disk, is not the one to report)."""
        try:
            for f in (self._pq, self._csv):
                if f is not None:
                    try:
                        f.close()
                    except OSError:
                        pass
        finally:
            for tmp in self._tmp.values():
                tmp.unlink(missing_ok=True)

    def table(self) -> dict[str, np.ndarray]:
        """The rows complete so far as columns (``keep``); only ``k`` and ``t`` without a row."""
        self._chunk()
        if self.columns is None:
            return {"k": np.zeros(0, dtype=np.int64), "t": np.zeros(0)}
        return {c: np.concatenate([g[c] for g in self._group]) for c in self.columns}

    def stats(self) -> dict[str, dict[str, float]]:
        """:func:`cosim.table.channel_stats` of the rows complete so far."""
        if self._rows:
            self._chunk()
        if self.columns is None:
            return {}
        return {c: s.result() for c, s in zip(self.columns[2:], self._stats, strict=True)
                if s.n}


_Shape = tuple[tuple[str, ...], tuple[type, ...]]


def _shape_verdicts(counts: Mapping[_Shape, int], fields: tuple[str, ...]) -> dict[_Shape, bool]:
    """Whether a message of each shape (its field names and value types, in its order) goes
    in the table: it carries every one of the channel's ``fields``, each a list or not as in
    the channel's most common such shape."""
    def listness(shape: _Shape) -> dict[str, bool] | None:
        kinds = dict(zip(*shape, strict=True))
        if not all(f in kinds for f in fields):
            return None
        return {f: kinds[f] is list for f in fields}

    complete = [(n, shape) for shape, n in counts.items() if listness(shape) is not None]
    ref = listness(max(complete, key=lambda c: c[0])[1]) if complete else None
    return {shape: ref is not None and listness(shape) == ref for shape in counts}


def _fits(d: Mapping[str, Any], lay: Layout, strict: bool) -> bool:
    """Whether a message's fields ``d`` fit the channel's layout."""
    if strict and len(d) != len(lay):
        return False
    for f, n in lay:
        v = d.get(f)
        if v is None or (type(v) is list) != (n is not None) or (n is not None
                                                                  and len(v) != n):
            return False
    return True


def _text(lay: Layout) -> str:
    return "(" + ", ".join(f if n is None else f"{f}[{n}]" for f, n in lay) + ")"


# ---- a journal's table, streamed -----------------------------------------------------------
def journal_layout(records: Iterable[tuple[str, bytes]]
                   ) -> tuple[dict[str, Layout], list[str]]:
    """The first pass over a journal: each channel's layout (the field set most of its data
    messages carry, each a list or not as in its most common complete shape: a stray message
    cannot displace the real ones) and the channels in the order first heard."""
    fields: dict[str, Counter[tuple[str, ...]]] = {}
    shapes: dict[str, Counter[Any]] = {}
    lengths: dict[str, dict[Any, dict[str, int]]] = {}
    for channel, payload in records:
        try:
            m = decode(payload)
        except WireError:
            continue
        if m.kind != "data" or m.k < 0:
            continue
        fields.setdefault(channel, Counter())[tuple(sorted(m.d))] += 1
        shape = (tuple(m.d), tuple(map(type, m.d.values())))
        shapes.setdefault(channel, Counter())[shape] += 1
        lengths.setdefault(channel, {}).setdefault(
            shape, {f: len(v) for f, v in m.d.items() if type(v) is list})
    layout: dict[str, Layout] = {}
    for channel, counts in fields.items():
        names = counts.most_common(1)[0][0]
        verdict = _shape_verdicts(shapes[channel], names)
        good = [s for s in shapes[channel] if verdict[s]]
        if not good:
            layout[channel] = tuple((f, None) for f in names)
            continue
        lens = lengths[channel][good[0]]
        kinds = dict(zip(*good[0], strict=True))
        layout[channel] = tuple((f, lens[f] if kinds[f] is list else None) for f in names)
    return layout, list(fields)


def table_of_journal(open_records: Any, folder: str | Path | None,
                     chunk_rows: int | None = None, keep: bool = False
                     ) -> tuple[TableWriter | None, int]:
    """The second pass: (a :class:`TableWriter` fed the journal's data messages, not closed,
    or None without one; the records left out as bad). ``open_records()`` is called a pass."""
    layout, first = journal_layout(open_records())
    if not layout:
        bad = 0
        for _channel, payload in open_records():
            try:
                decode(payload)
            except WireError:
                bad += 1
        return None, bad
    writer = TableWriter(layout, folder, layout=layout, first=first, chunk_rows=chunk_rows,
                         strict=False, keep=keep)
    bad = 0
    for channel, payload in open_records():
        try:
            m = decode(payload)
        except WireError:
            bad += 1
            continue
        if m.kind == "data" and m.k >= 0 and writer.add(channel, m.k, m.t, m.d) is not None:
            bad += 1
    return writer, bad + writer.late


def journal_table(records: Sequence[tuple[str, bytes]]) -> tuple[dict[str, np.ndarray], int]:
    """(table, records left out as bad) of a journal's records, in memory."""
    writer, bad = table_of_journal(lambda: records, None, keep=True)
    if writer is None:
        return {"k": np.zeros(0, dtype=np.int64), "t": np.zeros(0)}, bad
    return writer.table(), bad
