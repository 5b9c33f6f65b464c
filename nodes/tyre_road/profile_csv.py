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
from array import array
from pathlib import Path

import numpy as np

from cosim.errors import InputFileError
from cosim.safe_open import check_user_file, open_user_text

from .roads import SampledRoad


def _number(text: str) -> float | None:
    try:
        v = float(text)
    except ValueError:
        return None
    return v


def read_profile_csv(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Read (x, z_left, z_right) [m] from ``path``; raise InputFileError when malformed.

    The file is read line by line into typed arrays (24 bytes a sample, not the ~200 of a
    list of tuples of the lines), and refused above the ``profile`` limit of
    :mod:`cosim.safe_open` (256 MiB, ~1e7 samples; ``SUSCOSIM_MAX_PROFILE_MB``)."""
    path = str(path)
    check_user_file(path, "profile", "road.path")  # refused by its size before any read
    f = open_user_text(path, "profile", "road.path")

    cols: list[array] = []
    n_cols: int | None = None
    last_x = -math.inf
    seen_data_or_header = False
    i = 0
    with f:
        try:
            for i, raw in enumerate(f, start=1):
                line = raw.strip()
                if not line or line.startswith("#"):
                    continue
                fields = [x.strip() for x in line.split(",")]
                if not seen_data_or_header:
                    seen_data_or_header = True
                    if _number(fields[0]) is None:
                        continue  # header line
                if len(fields) not in (2, 3):
                    raise InputFileError(
                        path, f"expected 2 or 3 comma-separated columns (distance, height[, "
                              f"right height]), found {len(fields)}", i)
                if n_cols is None:
                    n_cols = len(fields)
                    cols = [array("d") for _ in fields]
                elif len(fields) != n_cols:
                    raise InputFileError(
                        path, f"row has {len(fields)} columns but earlier rows have {n_cols}",
                        i)
                values = []
                for j, text in enumerate(fields):
                    v = _number(text)
                    if v is None or not math.isfinite(v):
                        raise InputFileError(
                            path, f"column {j + 1} is not a finite number: {text!r}", i)
                    values.append(v)
                if values[0] <= last_x:
                    raise InputFileError(
                        path, f"distance must increase strictly: {values[0]} after {last_x}", i)
                last_x = values[0]
                for col, v in zip(cols, values, strict=True):
                    col.append(v)
        except UnicodeDecodeError:
            raise InputFileError(path, "not a text (UTF-8) file", i + 1) from None
    rows = len(cols[0]) if cols else 0
    if rows < 2:
        raise InputFileError(path, f"need at least 2 data rows, found {rows}")
    x, z_l = np.frombuffer(cols[0], dtype=float).copy(), np.frombuffer(cols[1], dtype=float)
    z_r = np.frombuffer(cols[2], dtype=float) if n_cols == 3 else z_l
    for j, z in enumerate((z_l, z_r)[: len(cols) - 1]):
        _check_physical(path, z, j + 2)
    return x, z_l.copy(), z_r.copy()


MAX_RELIEF_M = 10.0
"""Largest height a profile may reach from its first sample [m]: a durability track's profile
is its surface about the road's line (the vehicle models are vertical, no grade), and a proving
ground's largest feature is a kerb or a pothole of 0.1-0.2 m; 10 m leaves room for measured
roads not detrended, and refuses a number that is not a road (a 50 m or 1e300 m "bump")."""
MAX_STEP_M = 0.5
"""Largest height change between two adjacent samples [m]: a kerb strike is 0.1-0.15 m."""


def _check_physical(path: str | Path, z: np.ndarray, column: int | str) -> None:
    """InputFileError naming the first sample beyond :data:`MAX_RELIEF_M` or
    :data:`MAX_STEP_M` (``column``: the file's column, 1-based, or an MDF channel's quoted
    name; the line is its data row)."""
    relief, steps = np.abs(z - z[0]), np.abs(np.diff(z))
    for bad, what in (
            (relief > MAX_RELIEF_M, lambda i: f"height {float(z[i])!r} m is {relief[i]:.4g} m "
             f"from the first sample's (at most {MAX_RELIEF_M:g} m: not a road profile"),
            (steps > MAX_STEP_M, lambda i: f"the height changes by {steps[i]:.4g} m between "
             f"data rows {i + 1} and {i + 2} (at most {MAX_STEP_M:g} m between samples: a "
             "kerb is 0.15 m")):
        if bad.any():
            i = int(np.argmax(bad))
            raise InputFileError(str(path), f"column {column}: {what(i)}; heights are in metres)")


def csv_road(path: str | Path, speed: float, length: float | None = None,
             zero_start: bool = True) -> SampledRoad:
    """A :class:`SampledRoad` from a CSV profile; ``length`` defaults to the profile's extent."""
    x, zl, zr = read_profile_csv(path)
    x = x - x[0]
    if zero_start:
        zl, zr = zl - zl[0], zr - zr[0]
    return SampledRoad(x=x, z_left=zl, z_right=zr, speed=speed,
                       length=float(x[-1]) if length is None else length,
                       name=f"csv:{Path(path).name}")
