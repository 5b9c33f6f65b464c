"""CSV and Parquet channel sets.

CSV: a header row, then one row per sample, comma-separated numbers. The time column is
``t`` (or ``time``); a header ``name [unit]`` gives the unit (``plant/arm/ball_joint_z [N]``);
blank lines and lines starting with ``#`` are skipped. Parquet: one column per channel, the
unit in the field metadata under ``unit``.
"""

from __future__ import annotations

import csv
import io
import math
import re
from array import array
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from cosim.errors import InputFileError
from cosim.safe_open import open_user_text
from cosim.table_batches import arrow_column, numpy_column, parquet_errors

from .channel_set import ChannelSet

_TIME_NAMES = ("t", "time", "time_s", "Time")
_WITH_UNIT = re.compile(r"^(.*\S)\s*\[([^\]]*)\]$")


def _split(header: str) -> tuple[str, str]:
    m = _WITH_UNIT.match(header.strip())
    return (m.group(1), m.group(2).strip()) if m else (header.strip(), "")


def _time_column(names: list[str], path: str) -> int:
    for cand in _TIME_NAMES:
        if cand in names:
            return names.index(cand)
    raise InputFileError(path, "no time column: the header needs a 't' (or 'time') column", 1)


MAX_CSV_VALUES = 50_000_000
"""Most numbers a load CSV may hold (rows x columns; 400 MB as float64): a 10 kHz rig file of
1000 s with 4 channels."""


def read_csv(path: str | Path) -> ChannelSet:
    """A CSV table (``k``, a step index, dropped), read by NumPy's parser into one float64
    array (1e7 rows of 2 columns: 2 s, 0.35 GB); a file it does not take is read again row
    by row by :func:`_read_csv_rows`, which names the line of the problem."""
    import warnings

    path = str(path)
    with open_user_text(path, "loads", "load file") as fh:
        try:
            line, hline = fh.readline(), 1
            while line and (not line.strip() or line.lstrip().startswith("#")):
                line, hline = fh.readline(), hline + 1
            header = next(csv.reader([line]), None) if line.strip() else None
            if header and header[0].strip():
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")  # "input contained no data"
                    a = np.loadtxt(fh, dtype=float, delimiter=",", comments="#", ndmin=2,
                                   max_rows=MAX_CSV_VALUES // len(header) + 1)
                if a.shape[1] == len(header) and a.size <= MAX_CSV_VALUES and \
                        np.isfinite(a).all():
                    return _channels(path, header, a, hline)
        except (ValueError, UnicodeDecodeError, csv.Error):
            pass  # not InputFileError: the row reader says what and where
    return _read_csv_rows(path)


def _channels(path: str, header: list[str], a: np.ndarray, hline: int) -> ChannelSet:
    split = [_split(h) for h in header]
    names = [n for n, _ in split]
    if len(set(names)) != len(names):
        raise InputFileError(path, "a column name appears twice in the header", hline)
    it = _time_column(names, path)
    chans = {n: a[:, j].copy() for j, n in enumerate(names) if j != it and n != "k"}
    units = {n: u for n, u in split if n in chans}
    return ChannelSet(t=a[:, it].copy(), channels=chans, units=units)


def _read_csv_rows(path: str) -> ChannelSet:
    """:func:`read_csv` row by row, naming the line of a problem."""
    header: list[str] | None = None
    buf = array("d")
    lineno = hline = 0
    try:
        with open_user_text(path, "loads", "load file") as fh:
            for lineno, row in enumerate(csv.reader(fh), start=1):
                if not row or not row[0].strip() or row[0].lstrip().startswith("#"):
                    continue
                if header is None:  # checked before any data row
                    header, hline = row, lineno
                    _channels(path, header, np.empty((0, len(header))), hline)
                    continue
                if len(row) != len(header):
                    raise InputFileError(path, f"expected {len(header)} fields, got "
                                               f"{len(row)}", lineno)
                try:
                    vals = [float(v) for v in row]
                except ValueError:
                    raise InputFileError(path, "non-numeric value", lineno) from None
                if not all(math.isfinite(v) for v in vals):
                    raise InputFileError(path, "non-finite value", lineno)
                buf.extend(vals)
                if len(buf) > MAX_CSV_VALUES:
                    raise InputFileError(path, f"more than {MAX_CSV_VALUES:.3g} numbers (rows x "
                                               "columns): write it as Parquet or MDF 4, or "
                                               "split it", lineno)
    except UnicodeDecodeError:
        raise InputFileError(path, "not a text (UTF-8) file", lineno + 1) from None
    except csv.Error as exc:
        raise InputFileError(path, f"not a CSV file ({exc})", lineno + 1) from None
    if header is None:
        raise InputFileError(path, "empty file")
    return _channels(path, header, np.frombuffer(buf, dtype=float).reshape(-1, len(header)),
                     hline)


def write_chunks(path: str | Path, fmt: str, names: list[str], units: Mapping[str, str],
                 chunks: Iterable[Mapping[str, np.ndarray]], units_in_header: bool = False
                 ) -> int:
    """Write ``t`` and ``names`` of each chunk to ``path`` as ``csv`` (numbers as repr; header
    ``name [unit]`` with ``units_in_header``) or ``parquet`` (float64, metadata ``unit``)."""
    cols, rows = ["t", *names], 0
    if fmt == "csv":
        def head(n: str) -> str:
            u = units.get(n, "")
            return f"{n} [{u}]" if units_in_header and u else n

        with open(path, "w", newline="") as fh:
            csv.writer(fh).writerow([head(n) for n in cols])
            for chunk in chunks:
                body = io.StringIO(newline="")
                csv.writer(body).writerows(zip(*(np.asarray(chunk[c], dtype=float).tolist()
                                                 for c in cols), strict=True))
                fh.write(body.getvalue())
                rows += len(chunk["t"])
        return rows
    if fmt != "parquet":
        raise ValueError(f"table formats are csv and parquet, not {fmt!r}")
    import pyarrow as pa
    import pyarrow.parquet as pq

    schema = pa.schema([pa.field(n, pa.float64(), metadata={
        "unit": "s" if n == "t" else units.get(n, "")}) for n in cols])
    writer: Any = pq.ParquetWriter(str(path), schema)
    try:
        for chunk in chunks:
            arrays = [arrow_column(np.asarray(chunk[c], dtype=float)) for c in cols]
            writer.write_table(pa.Table.from_arrays(arrays, schema=schema))
            rows += len(chunk["t"])
    finally:
        writer.close()
    return rows


def write_csv(cs: ChannelSet, path: str | Path, units_in_header: bool = False
              ) -> dict[str, Any]:
    """CSV, ``t`` first (:func:`write_chunks`)."""
    write_chunks(path, "csv", list(cs.channels), cs.units, [{"t": cs.t, **cs.channels}],
                 units_in_header)
    return {}


def write_parquet(cs: ChannelSet, path: str | Path) -> dict[str, Any]:
    """Parquet, ``t`` first (:func:`write_chunks`)."""
    write_chunks(path, "parquet", list(cs.channels), cs.units, [{"t": cs.t, **cs.channels}])
    return {}


def read_parquet(path: str | Path) -> ChannelSet:
    """A Parquet table: its time column and every numeric column (``k`` dropped)."""
    import pyarrow.parquet as pq

    path = str(path)
    with parquet_errors(path):
        tab = pq.ParquetFile(path).read()
    names = tab.column_names
    it = _time_column(names, path)
    chans: dict[str, np.ndarray] = {}
    units: dict[str, str] = {}
    for j, n in enumerate(names):
        if j == it or n == "k":
            continue
        col = tab.column(n)
        try:
            chans[n] = numpy_column(col).astype(float)
        except (TypeError, ValueError):
            continue  # a text column: not a channel
        md = tab.schema.field(n).metadata or {}
        try:
            units[n] = md.get(b"unit", b"").decode()
        except UnicodeDecodeError:
            raise InputFileError(path, f"column {n!r}: its unit is not UTF-8 text") from None
    try:
        t = numpy_column(tab.column(names[it])).astype(float)
    except (TypeError, ValueError):
        raise InputFileError(path, f"the time column {names[it]!r} is not numeric") from None
    return ChannelSet(t=t, channels=chans, units=units)
