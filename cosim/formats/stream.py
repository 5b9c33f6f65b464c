"""A run's table read in chunks (``table.parquet`` a row group at a time, ``table.csv`` line
by line) and written as CSV or Parquet of the formats' layout (:mod:`.tables`): memory by
the chunk, not the run."""

from __future__ import annotations

import csv
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from cosim.errors import InputFileError
from cosim.table_batches import parquet_batches, parquet_errors

from .tables import write_chunks

BATCH_ROWS = 65536


def table_columns(src: str | Path) -> list[str]:
    """The column names of a run's ``table.parquet`` / ``table.csv``."""
    src = Path(src)
    if src.suffix == ".parquet":
        import pyarrow.parquet as pq

        with parquet_errors(src):
            return list(pq.ParquetFile(src).schema_arrow.names)
    with open(src, newline="") as fh:
        head = next(csv.reader(fh), None)
    if not head:
        raise InputFileError(str(src), "no header row", 1)
    return head


def iter_chunks(src: str | Path, names: list[str], rows: int | None = None
                ) -> Iterator[dict[str, np.ndarray]]:
    """The columns ``names`` of a run's table in chunks of up to ``rows`` rows."""
    src = Path(src)
    rows = BATCH_ROWS if rows is None else rows
    if src.suffix == ".parquet":
        with parquet_errors(src):
            yield from parquet_batches(src, names, rows)  # a row group at a time
        return
    with open(src, newline="") as fh:
        reader = csv.reader(fh)
        head = next(reader, None) or []
        idx = [head.index(n) for n in names]
        buf: list[list[str]] = []
        for lineno, row in enumerate(reader, start=2):
            if len(row) != len(head):
                raise InputFileError(str(src), f"expected {len(head)} fields, got {len(row)}",
                                     lineno)
            buf.append([row[i] for i in idx])
            if len(buf) >= rows:
                yield _columns(buf, names, str(src))
                buf = []
        if buf:
            yield _columns(buf, names, str(src))


def _columns(rows: list[list[str]], names: list[str], src: str) -> dict[str, np.ndarray]:
    try:
        arr = np.asarray(rows, dtype=float).reshape(len(rows), len(names))
    except ValueError:
        raise InputFileError(src, "non-numeric value") from None
    return {n: arr[:, j] for j, n in enumerate(names)}


def write_stream(src: str | Path, path: str | Path, fmt: str, names: list[str],
                 units: dict[str, str], units_in_header: bool = True) -> int:
    """Write ``t`` and ``names`` of the table ``src`` to ``path`` as ``fmt``; the rows written."""
    if fmt not in ("csv", "parquet"):
        raise ValueError(f"streamed formats are csv and parquet, not {fmt!r}")
    return write_chunks(path, fmt, names, units, iter_chunks(src, ["t", *names]),
                        units_in_header)
