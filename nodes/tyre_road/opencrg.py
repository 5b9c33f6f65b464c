"""Measured road surface from an OpenCRG file (``.crg``, ASAM OpenCRG 1.x; via ``pyopencrg``).

An OpenCRG file holds the road's elevation on a (u, v) grid: u along the reference line, v
across it (positive to the left, as ISO 8855's y). The two wheel tracks are cut out of the
surface as long sections at

    v_left  = v_offset + track_width / 2,     v_right = v_offset - track_width / 2,

sampled at every cross section (the file's u increment) and interpolated bilinearly by
pyopencrg; the vehicle drives along u from ``u_start`` (default the file's first cross
section). ``track_width`` defaults to the vehicle's track, 1.411 m (the 7-DOF model's and
the double-wishbone corner's, thesis Ch. 4); ``v_offset`` is the vehicle centreline's lateral
offset from the reference line.

Heights are the elevation grid relative to the reference line (``reference = "grid"``, the
default: the road's unevenness, what loads the suspension); ``reference = "full"`` adds the
reference line's slope and the banking (a long grade then becomes a height drift). The file's
modifiers are applied as a simulator does. As for a CSV profile, each track is shifted to start
at 0 (``zero_start``) and the distance to start at s = 0.

Every problem (not an OpenCRG file, a track outside the road's width, missing data on a
track) raises :class:`cosim.errors.InputFileError` naming the file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from cosim.errors import InputFileError
from cosim.safe_open import check_user_file, open_user_file

from .roads import SampledRoad

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


def opencrg_road(path: str | Path, speed: float, length: float | None = None,
                 track_width: float = VEHICLE_TRACK_M, v_offset: float = 0.0,
                 u_start: float | None = None, reference: str = "grid",
                 zero_start: bool = True) -> SampledRoad:
    """A :class:`SampledRoad` of the two wheel tracks; ``length`` defaults to the road's."""
    x, zl, zr = crg_tracks(path, track_width, v_offset, u_start, reference)
    if zero_start:
        zl, zr = zl - zl[0], zr - zr[0]
    if length is not None and length > x[-1] + 1e-9:
        raise InputFileError(str(path), f"road.length_m {length:g} m is longer than the road "
                                        f"from u_start ({x[-1]:g} m)")
    return SampledRoad(x=x, z_left=zl, z_right=zr, speed=speed,
                       length=float(x[-1]) if length is None else length,
                       name=f"opencrg:{Path(path).name}")
