"""Measured road profiles: CSV, ASAM MDF 4 and OpenCRG files (``[road] type = "csv" |
"mdf4" | "opencrg"``; docs/data_formats.md). Each becomes a :class:`SampledRoad` whose distance
starts at s = 0 and, with ``zero_start`` (default), each track at height 0 (the vehicle starts at
static equilibrium on a flat road, so a non-zero first height would be a step at t = 0); its
``length`` defaults to the profile's extent. Every problem raises
:class:`cosim.errors.InputFileError` naming the file and the line or the channel.

**CSV** (the thesis digitised MIRA / LTC pavé tracks as height against distance; Ch. 4 Sec.
4.5): one sample per line, comma-separated, ``distance [m], height [m][, right height [m]]``.
With two columns both tracks get the same height. Blank lines and lines starting with ``#`` are
ignored; the first non-comment line may be a header (a line whose first field is not a number).
Distances must be finite and strictly increasing; at least two samples are needed.

**MDF 4** (a profilometer's or a track survey's), channels by name: ``left`` the left track's
height, ``right`` the right track's (default: the left one for both), and the distance along
the road either as a channel ``distance`` [m] or from the file's time master times
``recorded_speed_kmh`` (the speed the profile was recorded at). Height units m, mm, cm or um
(converted to m; an empty unit is taken as m); distances must increase strictly.

**OpenCRG** (``.crg``, ASAM OpenCRG 1.x; via ``pyopencrg``): the road's elevation on a (u, v)
grid, u along the reference line, v across it (positive to the left, as ISO 8855's y). The two
wheel tracks are cut out of the surface as long sections at

    v_left  = v_offset + track_width / 2,     v_right = v_offset - track_width / 2,

sampled at every cross section (the file's u increment) and interpolated bilinearly by
pyopencrg; the vehicle drives along u from ``u_start`` (default the file's first cross
section). ``track_width`` defaults to the vehicle's track, 1.411 m (the 7-DOF model's and
the double-wishbone corner's, thesis Ch. 4); ``v_offset`` is the vehicle centreline's lateral
offset from the reference line. Heights are the elevation grid relative to the reference line
(``reference = "grid"``, the default: the road's unevenness, what loads the suspension);
``reference = "full"`` adds the reference line's slope and the banking (a long grade then
becomes a height drift). The file's modifiers are applied as a simulator does.
"""

from __future__ import annotations

import math
from array import array
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from cosim.errors import InputFileError
from cosim.formats.mdf4 import read_mdf4
from cosim.formats.units import to_si_factor
from cosim.safe_open import check_user_file, open_user_file, open_user_text

from .roads import KMH, SampledRoad


def _road(path: str | Path, kind: str, x: np.ndarray, zl: np.ndarray, zr: np.ndarray,
          speed: float, length: float | None, zero_start: bool,
          extent: str | None = None) -> SampledRoad:
    """The :class:`SampledRoad` of a measured profile (module docstring); a ``length`` [m]
    beyond the profile is an error naming the ``extent`` it overruns (None: no check)."""
    x = x - x[0]
    if extent and length is not None and length > x[-1] + 1e-9:
        raise InputFileError(str(path), f"road.length_m {length:g} m is longer than the "
                                        f"{extent} ({x[-1]:g} m)")
    if zero_start:
        zl, zr = zl - zl[0], zr - zr[0]
    return SampledRoad(x=x, z_left=zl, z_right=zr, speed=speed,
                       length=float(x[-1]) if length is None else length,
                       name=f"{kind}:{Path(path).name}")


# ------------------------------------------------------------------------------------ CSV


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


# ------------------------------------------------------------------------------------ MDF 4


def read_profile_mdf(path: str | Path, left: str, right: str | None = None,
                     distance: str | None = None, recorded_speed_kmh: float | None = None
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, z_left, z_right) [m] from an MDF 4 file (see the module docstring)."""
    path = str(path)
    check_user_file(path, "mdf", "road.path")
    cs = read_mdf4(path)

    def channel(name: str, quantity: str = "length") -> np.ndarray:
        if name not in cs.channels:
            raise InputFileError(path, f"no channel {name!r} (the file has "
                                       + ", ".join(list(cs.channels)[:12]) + ")")
        f = to_si_factor(cs.units.get(name, ""), quantity)
        if f is None:
            raise InputFileError(path, f"channel {name!r} has unit {cs.units[name]!r}: a "
                                       "length (m, mm) is expected")
        x = cs.channels[name] * f
        if not np.all(np.isfinite(x)):
            raise InputFileError(path, f"channel {name!r} has non-finite values")
        return x

    zl = channel(left)
    zr = channel(right) if right else zl.copy()
    if distance is not None:
        x = channel(distance)
    elif recorded_speed_kmh is not None:
        x = np.asarray(cs.t, dtype=float) * recorded_speed_kmh * KMH
    else:
        raise InputFileError(path, "the distance along the road is unknown: give road.distance "
                                   "(a channel in m) or road.recorded_speed_kmh")
    if x.size < 2:
        raise InputFileError(path, f"need at least 2 samples, found {x.size}")
    if np.any(np.diff(x) <= 0):
        i = int(np.argmax(np.diff(x) <= 0)) + 1
        raise InputFileError(path, f"distance must increase strictly: {x[i]:g} m after "
                                   f"{x[i - 1]:g} m (sample {i})")
    for name, z in ((left, zl), (right, zr)):  # the CSV profile's bounds
        if name:
            _check_physical(path, z, repr(name))
    return x, zl, zr


# ---------------------------------------------------------------------------------- OpenCRG


VEHICLE_TRACK_M = 1.411
"""Default track width [m]: the vehicle's (nodes/plant: FullVehicleParams.track, and the
double-wishbone corner's half track 0.7055 m)."""


def _check_data_reference(path: str) -> None:
    """A ``$ROAD_CRG_FILE`` block (the data in another file) must name a regular file inside
    the CRG file's folder, as written: pyopencrg expands ``$VARIABLES`` in it (an environment
    variable would leak into the error) and reads any absolute path, so both are refused
    here, before pyopencrg sees the file."""
    from pyopencrg.io import cut_block  # type: ignore[import-untyped]

    lines: list[str] = []
    with open_user_file(path, "crg", "road.path") as fh:
        for raw in fh:  # the header, up to its $$$$ separator (the data is not read)
            line = raw.decode("latin-1").rstrip("\r\n")
            if line.startswith("$$$$") or len(lines) > 100_000:
                break
            lines.append(line)
    block, _ = cut_block(lines, "ROAD_CRG_FILE")
    if block is None:
        return
    ref = "".join(ln.split("!", 1)[0].strip() for ln in block if not ln.startswith("*"))
    if "$" in ref or ref.startswith("~") or Path(ref).is_absolute():
        raise InputFileError(path, f"road.path: $ROAD_CRG_FILE names {ref!r}: a data file is "
                                   "taken only as a plain path relative to the CRG file's "
                                   "folder (no $VARIABLE, no ~, not absolute)")
    folder = Path(path).parent
    check_user_file(folder / ref, "crg", "road.path ($ROAD_CRG_FILE)", inside=folder)


def read_crg(path: str | Path):
    """The pyopencrg road of ``path``, modifiers applied; InputFileError when unreadable."""
    import warnings

    import pyopencrg

    path = str(path)
    check_user_file(path, "crg", "road.path")
    _check_data_reference(path)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # pyopencrg warns of legal-but-odd files
            return pyopencrg.read(path, apply_mods=True, check=True)
    except Exception as exc:  # CrgCheckError, ValueError, struct errors ... on a bad file
        raise InputFileError(path, f"not a readable OpenCRG file ({type(exc).__name__}: "
                                   f"{exc})") from None


def crg_tracks(path: str | Path, track_width: float = VEHICLE_TRACK_M, v_offset: float = 0.0,
               u_start: float | None = None, reference: str = "grid"
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u - u_start, z_left, z_right) [m] of the two wheel tracks of an OpenCRG road."""
    if reference not in ("grid", "full"):
        raise ValueError(f"reference must be 'grid' or 'full', got {reference!r}")
    road = read_crg(path)
    path = str(path)
    u = np.asarray(road.u, dtype=float)
    if u_start is not None:
        if not u[0] <= u_start < u[-1]:
            raise InputFileError(path, f"u_start {u_start} m outside the road's u range "
                                       f"[{u[0]:g}, {u[-1]:g}] m")
        u = np.concatenate(([u_start], u[u > u_start]))
    if u.size < 2:
        raise InputFileError(path, "fewer than 2 cross sections from u_start on")
    tracks = []
    for side, v in (("left", v_offset + track_width / 2), ("right", v_offset - track_width / 2)):
        if not road.v_min - 1e-9 <= v <= road.v_max + 1e-9:
            raise InputFileError(path, f"the {side} wheel track at v = {v:+.4g} m is outside "
                                       f"the road's width [{road.v_min:g}, {road.v_max:g}] m "
                                       "(road.track_width / road.v_offset)")
        v_in = min(max(v, road.v_min), road.v_max)
        z = np.asarray(road.uv_to_z(u, np.full(u.shape, v_in),
                                    grid_only=reference == "grid"), dtype=float)
        bad = ~np.isfinite(z)
        if bad.any():
            raise InputFileError(path, f"no elevation data on the {side} wheel track (v = "
                                       f"{v:+.4g} m) at u = {u[bad][0]:g} m")
        tracks.append(z)
    return u - u[0], tracks[0], tracks[1]


def measured_road(kind: str, path: str | Path, speed: float, length: float | None = None,
                  zero_start: bool = True, **reader: Any) -> SampledRoad:
    """A :class:`SampledRoad` of a ``kind`` ("csv", "mdf4", "opencrg") profile read by
    :func:`read_profile_csv`, :func:`read_profile_mdf` or :func:`crg_tracks` (``reader``: its
    keywords); a ``length`` beyond an MDF profile or a CRG road is an error."""
    read: dict[str, Callable[..., tuple[np.ndarray, np.ndarray, np.ndarray]]] = {
        "csv": read_profile_csv, "mdf4": read_profile_mdf, "opencrg": crg_tracks}
    extent = {"mdf4": "profile", "opencrg": "road from u_start"}.get(kind)
    return _road(path, kind, *read[kind](path, **reader), speed, length, zero_start, extent)
