"""From journal records to a table of every channel against time, and its statistics.

Columns: ``k``, ``t`` [s], then ``<node>/<channel>/<field>`` (a per-corner list field becomes
``<field>[i]``). A row is a communication step; a step some channel never delivered (a run
that ended early) is left out of the table, so every row is complete.
"""

from __future__ import annotations

import csv
import math
from collections import Counter
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from cosim.errors import WireError
from cosim.wire import Message, decode

Table = dict[str, np.ndarray]


def build_table(records: Iterable[tuple[str, bytes]]) -> tuple[Table, int]:
    """Table of the data records (hello/control and undecodable records are skipped).

    A channel's fields are those most of its messages carry; for each step the first message
    that carries them all is used, so a stray or forged message (wrong fields) on a channel
    cannot displace the real one. Returns (table, number of records left out as bad).
    """
    per_channel: dict[str, list[Message]] = {}
    bad = 0
    for channel, payload in records:
        try:
            msg = decode(payload)
        except WireError:
            bad += 1
            continue
        if msg.kind == "data" and msg.k >= 0:
            per_channel.setdefault(channel, []).append(msg)
    rows: dict[str, dict[int, dict[str, Any]]] = {}
    fields_of: dict[str, tuple[str, ...]] = {}
    times: dict[int, float] = {}
    for channel, msgs in per_channel.items():
        fields = Counter(tuple(sorted(m.d)) for m in msgs).most_common(1)[0][0]
        fields_of[channel] = fields
        box = rows.setdefault(channel, {})
        for m in msgs:
            if m.k in box or not all(f in m.d for f in fields):
                bad += 1
                continue
            if any(isinstance(m.d[f], list) != isinstance(msgs[0].d[f], list) for f in fields):
                bad += 1
                continue
            box[m.k] = m.d
            times.setdefault(m.k, m.t)
    if not rows:
        return {"k": np.zeros(0, dtype=int), "t": np.zeros(0)}, bad
    ks = sorted(set.intersection(*(set(v) for v in rows.values())))
    table: Table = {"k": np.asarray(ks, dtype=np.int64),
                    "t": np.asarray([times[k] for k in ks], dtype=float)}
    for channel in sorted(rows):
        box = rows[channel]
        for name in fields_of[channel]:
            arr = np.asarray([box[k][name] for k in ks], dtype=float)
            if arr.ndim == 2:
                for i in range(arr.shape[1]):
                    table[f"{channel}/{name}[{i}]"] = arr[:, i]
            else:
                table[f"{channel}/{name}"] = arr
    return table, bad


def write_csv(table: Table, path: str | Path) -> None:
    """CSV with a header row; numbers in full precision (repr)."""
    cols = list(table)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(cols)
        n = len(table["t"])
        data = [table[c].tolist() for c in cols]
        for i in range(n):
            w.writerow([col[i] for col in data])


def write_parquet(table: Table, path: str | Path) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    pq.write_table(pa.table({c: pa.array(v) for c, v in table.items()}), path)


def read_table(path: str | Path) -> Table:
    """Read a table written by :func:`write_parquet` or :func:`write_csv`."""
    path = Path(path)
    if path.suffix == ".parquet":
        import pyarrow.parquet as pq

        t = pq.read_table(path)
        return {c: t.column(c).to_numpy() for c in t.column_names}
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    cols = rows[0]
    arr = np.asarray(rows[1:], dtype=float).reshape(len(rows) - 1, len(cols))
    return {c: arr[:, i] for i, c in enumerate(cols)}


def channel_stats(table: Table) -> dict[str, dict[str, float]]:
    """Per column: max, min, peak (largest magnitude, signed), mean, rms, std."""
    out: dict[str, dict[str, float]] = {}
    for name, x in table.items():
        if name in ("k", "t") or x.size == 0:
            continue
        i = int(np.argmax(np.abs(x)))
        out[name] = {
            "max": float(x.max()), "min": float(x.min()), "peak": float(x[i]),
            "t_peak": float(table["t"][i]), "mean": float(x.mean()),
            "rms": float(math.sqrt(np.mean(x * x))), "std": float(x.std()),
        }
    return out


def export(table: Table, folder: str | Path, stem: str = "table") -> dict[str, str]:
    """Write ``<stem>.csv`` and ``<stem>.parquet`` in ``folder``; return their paths."""
    folder = Path(folder)
    paths = {"csv": str(folder / f"{stem}.csv"), "parquet": str(folder / f"{stem}.parquet")}
    write_csv(table, paths["csv"])
    write_parquet(table, paths["parquet"])
    return paths


RECOVERED_STEM = "table.recovered"
"""Where ``suscosim export`` writes a table it must not put in place of ``table.*``."""


def table_rows(folder: str | Path, stem: str = "table") -> int | None:
    """Rows of the table already in ``folder`` (its parquet metadata, else its CSV's lines),
    or None when there is none (or it cannot be read)."""
    folder = Path(folder)
    pq_path, csv_path = folder / f"{stem}.parquet", folder / f"{stem}.csv"
    if pq_path.is_file():
        try:
            import pyarrow.parquet as pq

            return int(pq.ParquetFile(pq_path).metadata.num_rows)
        except Exception:  # torn or foreign: try the CSV
            pass
    if csv_path.is_file():
        try:
            with open(csv_path, "rb") as f:
                return max(0, sum(1 for line in f if line.strip()) - 1)
        except OSError:
            return None
    return None


def export_target(folder: str | Path, rows: int, damaged: bool) -> tuple[str, str]:
    """Where a table of ``rows`` rebuilt from a journal may go without ever replacing a
    table silently by a smaller one: (stem, why). ``table`` (why = "") unless the journal was
    ``damaged`` (records skipped in its middle) or a ``table.*`` with more rows is already in
    ``folder``: then ``table.recovered``, alongside, and ``why`` says which."""
    before = table_rows(folder)
    if damaged:
        return RECOVERED_STEM, "the journal is damaged"
    if before is not None and before > rows:
        return RECOVERED_STEM, f"the table already there has more rows ({before} > {rows})"
    return "table", ""


def export_safely(table: Table, folder: str | Path, damaged: bool) -> tuple[dict[str, str], str]:
    """:func:`export` to :func:`export_target`'s place: (paths written, why alongside)."""
    stem, why = export_target(folder, len(table["t"]), damaged)
    return export(table, folder, stem), why
