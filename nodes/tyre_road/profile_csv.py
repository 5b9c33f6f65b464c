"""Measured road profile from a CSV file (the thesis digitised MIRA / LTC pavé tracks as height
against distance; Ch. 4 Sec. 4.5).

Format: one sample per line, comma-separated, ``distance [m], height [m][, right height [m]]``.
With two columns both tracks get the same height. Blank lines and lines starting with ``#`` are
ignored; the first non-comment line may be a header (a line whose first field is not a number).
Distances must be finite and strictly increasing; at least two samples are needed.

By default the profile is shifted so that each track starts at height 0 (the vehicle starts at
static equilibrium on a flat road, so a non-zero first height would be a step at t = 0); the
distance is shifted so that the first sample is at s = 0.

Every problem raises :class:`cosim.errors.InputFileError` naming the file and the line.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from cosim.errors import InputFileError

from .roads import SampledRoad


def _number(text: str) -> float | None:
    try:
        v = float(text)
    except ValueError:
        return None
    return v


def read_profile_csv(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Read (x, z_left, z_right) [m] from ``path``; raise InputFileError when malformed."""
    path = str(path)
    try:
        with open(path, encoding="utf-8") as f:
            lines = f.read().splitlines()
    except FileNotFoundError:
        raise InputFileError(path, "file not found") from None
    except UnicodeDecodeError:
        raise InputFileError(path, "not a text (UTF-8) file") from None
    except OSError as e:
        raise InputFileError(path, f"cannot read: {e.strerror}") from None

    rows: list[tuple[float, ...]] = []
    n_cols: int | None = None
    seen_data_or_header = False
    for i, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        fields = [f.strip() for f in line.split(",")]
        if not seen_data_or_header:
            seen_data_or_header = True
            if _number(fields[0]) is None:
                continue  # header line
        if len(fields) not in (2, 3):
            raise InputFileError(
                path, f"expected 2 or 3 comma-separated columns (distance, height[, right "
                      f"height]), found {len(fields)}", i)
        if n_cols is None:
            n_cols = len(fields)
        elif len(fields) != n_cols:
            raise InputFileError(
                path, f"row has {len(fields)} columns but earlier rows have {n_cols}", i)
        values = []
        for j, f in enumerate(fields):
            v = _number(f)
            if v is None or not math.isfinite(v):
                raise InputFileError(path, f"column {j + 1} is not a finite number: {f!r}", i)
            values.append(v)
        if rows and values[0] <= rows[-1][0]:
            raise InputFileError(
                path, f"distance must increase strictly: {values[0]} after {rows[-1][0]}", i)
        rows.append(tuple(values))
    if len(rows) < 2:
        raise InputFileError(path, f"need at least 2 data rows, found {len(rows)}")
    a = np.array(rows, dtype=float)
    z_r = a[:, 2] if a.shape[1] == 3 else a[:, 1]
    return a[:, 0], a[:, 1], z_r.copy()


def csv_road(path: str | Path, speed: float, length: float | None = None,
             zero_start: bool = True) -> SampledRoad:
    """A :class:`SampledRoad` from a CSV profile; ``length`` defaults to the profile's extent."""
    x, zl, zr = read_profile_csv(path)
    x = x - x[0]
    if zero_start:
        zl, zr = zl - zl[0], zr - zr[0]
    if length is None:
        length = float(x[-1])
    return SampledRoad(x=x, z_left=zl, z_right=zr, speed=speed, length=length,
                       name=f"csv:{Path(path).name}")
