"""A Parquet table read in row batches, one row group at a time (the report, batch
fatigue and the bench read a run's table without holding it whole)."""

from __future__ import annotations

import threading
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from .errors import InputFileError

BATCH_ROWS = 65_536  # rows yielded at a time at most (~0.5 MB a column)



def _import_pyarrow() -> None:
    try:
        import pyarrow.parquet  # noqa: F401
    except ImportError:  # the table's writer or reader says so when it needs it
        pass


def warm_pyarrow() -> None:
    """Import pyarrow.parquet on a daemon thread: a process that writes or reads a table at
    its end (recorder, orchestrator) does it while the run starts, not after its last step
    (the import takes 0.1 s on a quiet machine, seconds on a loaded one)."""
    threading.Thread(target=_import_pyarrow, name="pyarrow-import", daemon=True).start()

def arrow_column(x: np.ndarray) -> Any:
    """A numeric numpy column as a pyarrow Array over the same memory, the same array as
    ``pa.array(x)`` (files byte for byte) without its first-call probe that imports pandas
    (0.2-0.5 s of every recorder and export; other dtypes: ``pa.array``)."""
    import pyarrow as pa

    x = np.ascontiguousarray(x)
    if x.dtype.kind not in "fiu" or x.ndim != 1:
        return pa.array(x)
    return pa.Array.from_buffers(pa.from_numpy_dtype(x.dtype), x.size, [None, pa.py_buffer(x)])


def numpy_column(col: Any) -> np.ndarray:
    """A pyarrow Array or ChunkedArray as numpy, the same array as its ``to_numpy()`` (a
    column of one chunk: a read-only view) without its first call's pandas import (0.2-0.5
    s of a run's end): a numeric chunk without nulls is read from its buffer; other columns
    (text, nulls) go through pyarrow."""
    import pyarrow as pa

    if not isinstance(col, pa.ChunkedArray):
        col = pa.chunked_array([col])
    parts: list[np.ndarray] = []
    for c in col.chunks:
        kind = ("f" if pa.types.is_floating(c.type) else "i" if pa.types.is_signed_integer(
            c.type) else "u" if pa.types.is_unsigned_integer(c.type) else None)
        if kind is None or c.null_count:
            return np.asarray(col.to_numpy())
        dt = np.dtype(f"{kind}{c.type.bit_width // 8}")
        parts.append(np.frombuffer(c.buffers()[1], dt, len(c), c.offset * dt.itemsize))
    if len(parts) == 1:
        return parts[0]
    return np.concatenate(parts) if parts else np.asarray(col.to_numpy())


@contextmanager
def parquet_errors(path: str | Path, pass_missing: bool = False) -> Iterator[None]:
    """pyarrow's errors on a file that is not a readable Parquet table as an InputFileError
    naming it (``pass_missing``: a missing file's OSError passes as it is)."""
    try:
        yield
    except InputFileError:
        raise
    except Exception as exc:  # pyarrow raises several types for a bad file
        if pass_missing and isinstance(exc, OSError) and not Path(path).is_file():
            raise
        raise InputFileError(str(path), f"not a readable Parquet file ({exc})") from None


def parquet_batches(path: Path, columns: Sequence[str], rows: int = BATCH_ROWS
                    ) -> Iterator[dict[str, np.ndarray]]:
    """``{column: float values}`` of a Parquet file, one row group at a time (cut to at most
    ``rows`` rows), without threads or pre-buffering (pyarrow's ``iter_batches`` reads
    ahead); a file of larger row groups goes through ``iter_batches``."""
    import pyarrow.parquet as pq

    f = pq.ParquetFile(path, pre_buffer=False)
    md = f.metadata
    cols = list(columns)
    if md.num_row_groups and max(md.row_group(i).num_rows
                                 for i in range(md.num_row_groups)) > 4 * rows:
        for b in f.iter_batches(rows, columns=cols, use_threads=False):
            yield {c: numpy_column(b.column(i)).astype(float, copy=False)
                   for i, c in enumerate(cols)}
        return
    for g in range(md.num_row_groups):
        tab = f.read_row_group(g, columns=cols, use_threads=False)
        arrs = [numpy_column(tab.column(i)).astype(float, copy=False)
                for i in range(len(cols))]
        del tab
        for i in range(0, arrs[0].size if arrs else 0, rows):
            yield {c: a[i:i + rows] for c, a in zip(cols, arrs, strict=True)}


def uniform_grid_size(t0: float, t1: float, h: float) -> int:
    """Samples of the uniform grid t0, t0 + h, ... that lie within [t0, t1] [s]."""
    return int(np.floor((t1 - t0) / h * (1 + 1e-12) + 1e-9)) + 1


def resampled(batches: Iterator[dict[str, np.ndarray]], h: float
              ) -> Iterator[dict[str, np.ndarray]]:
    """The batches of a table with a non-uniform ``t`` (``run.h = "auto"``) on the uniform
    grid t0 + i h [s] from its first row, linearly interpolated (for PSDs, ride metrics)."""
    prev: dict[str, np.ndarray] | None = None
    t0: float | None = None
    i_next = 0  # the next grid point's index
    for b in batches:
        if t0 is None:
            t0 = float(b["t"][0])
        cur = b if prev is None else {c: np.concatenate([prev[c], v]) for c, v in b.items()}
        t = cur["t"]
        i_last = uniform_grid_size(t0, float(t[-1]), h) - 1
        if i_last >= i_next:
            grid = t0 + h * np.arange(i_next, i_last + 1)
            out = {c: np.interp(grid, t, v) for c, v in cur.items() if c != "t"}
            out["t"] = grid
            yield out
            i_next = i_last + 1
        prev = {c: v[-1:] for c, v in cur.items()}
