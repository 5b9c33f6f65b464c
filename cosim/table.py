"""A run's table (columns ``k``, ``t`` [s], then ``<node>/<channel>/<field>``, a per-corner
list field as ``<field>[i]``; made by :mod:`cosim.table_writer`): its files, written and read,
and its statistics."""

from __future__ import annotations

import csv
import math
import os
import threading
from collections.abc import Callable
from pathlib import Path

import numpy as np

from cosim.errors import InputFileError
from cosim.table_batches import arrow_column, numpy_column, parquet_errors

Table = dict[str, np.ndarray]


def write_csv(table: Table, path: str | Path) -> None:
    """CSV with a header row; numbers in full precision (repr), rows ended by CRLF (what
    ``csv.writer`` writes; the body is joined directly: a number never needs quoting)."""
    cols = list(table)
    with open(path, "w", newline="") as f:
        csv.writer(f).writerow(cols)
        for start in range(0, len(table["t"]), 4096):  # bounded memory for long runs
            chunk = [map(str, table[c][start:start + 4096].tolist()) for c in cols]
            f.writelines(",".join(row) + "\r\n" for row in zip(*chunk, strict=True))


def write_parquet(table: Table, path: str | Path) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    pq.write_table(pa.table({c: arrow_column(v) for c, v in table.items()}), path)


def read_table(path: str | Path, keep: Callable[[str], bool] | None = None) -> Table:
    """A table file (Parquet or CSV, by its suffix), the columns ``keep`` accepts (``k`` and
    ``t`` always); InputFileError naming a file (and CSV line) that is not one."""
    path = Path(path)

    def wanted(name: str) -> bool:
        return keep is None or name in ("k", "t") or keep(name)

    if path.suffix == ".parquet":
        import pyarrow.parquet as pq

        with parquet_errors(path, pass_missing=True):
            f = pq.ParquetFile(path)
            t = f.read(columns=[n for n in f.schema_arrow.names if wanted(n)])
            return {c: numpy_column(t.column(c)) for c in t.column_names}
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows or not rows[0]:
        raise InputFileError(str(path), "no header row", 1)
    cols = rows[0]
    cut = [i for i, c in enumerate(cols) if wanted(c)]
    try:
        arr = np.asarray(rows[1:], dtype=float).reshape(len(rows) - 1, len(cols))
    except ValueError:  # say where
        for lineno, row in enumerate(rows[1:], start=2):
            if len(row) != len(cols):
                raise InputFileError(str(path), f"expected {len(cols)} fields, got "
                                                f"{len(row)}", lineno) from None
            try:
                [float(x) for x in row]
            except ValueError:
                raise InputFileError(str(path), "non-numeric value", lineno) from None
        raise
    return {cols[i]: arr[:, i] for i in cut}


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
    """Write ``<stem>.csv``, ``.parquet`` in ``folder``, each aside and renamed; the paths."""
    folder = Path(folder)
    paths = {"csv": str(folder / f"{stem}.csv"), "parquet": str(folder / f"{stem}.parquet")}
    for kind, write in (("csv", write_csv), ("parquet", write_parquet)):
        path = Path(paths[kind])
        tmp = path.with_name(f".{path.name}.{os.getpid()}.{threading.get_ident()}.tmp")
        try:
            write(table, tmp)
            os.replace(tmp, path)
        finally:
            tmp.unlink(missing_ok=True)
    return paths


RECOVERED_STEM = "table.recovered"
"""Where ``suscosim export`` writes a table it must not put in place of ``table.*``."""


def table_rows(folder: str | Path, stem: str = "table") -> int | None:
    """Rows of the table in ``folder`` (Parquet metadata, else CSV lines), or None."""
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
    """(stem, why) for a table of ``rows`` rebuilt from a journal: ``table``, or
    ``table.recovered`` when the journal was ``damaged`` or a larger table is there."""
    before = table_rows(folder)
    if damaged:
        return RECOVERED_STEM, "the journal is damaged"
    if before is not None and before > rows:
        return RECOVERED_STEM, f"the table already there has more rows ({before} > {rows})"
    return "table", ""
