"""Measured road profile from an ASAM MDF 4 file (a profilometer's or a track survey's).

Channels (by name): ``left`` the left track's height, ``right`` the right track's (default:
the left one for both), and the distance along the road either as a channel ``distance`` [m]
or from the file's time master times ``recorded_speed_kmh`` (the speed the profile was
recorded at). Height units m, mm, cm or um (converted to m; an empty unit is taken as m);
distances must increase strictly. As for a CSV profile, each track is shifted to start at 0
(``zero_start``) and the distance to start at s = 0.

Every problem raises :class:`cosim.errors.InputFileError` naming the file and the channel.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from cosim.errors import InputFileError
from cosim.formats.mdf4 import read_mdf4
from cosim.formats.units import to_si_factor
from cosim.safe_open import check_user_file

from .profile_csv import _check_physical
from .roads import KMH, SampledRoad


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


def mdf_road(path: str | Path, speed: float, left: str, right: str | None = None,
             distance: str | None = None, recorded_speed_kmh: float | None = None,
             length: float | None = None, zero_start: bool = True) -> SampledRoad:
    """A :class:`SampledRoad` from an MDF 4 profile; ``length`` defaults to its extent."""
    x, zl, zr = read_profile_mdf(path, left, right, distance, recorded_speed_kmh)
    x = x - x[0]
    if length is not None and length > x[-1] + 1e-9:
        raise InputFileError(str(path), f"road.length_m {length:g} m is longer than the "
                                        f"profile ({x[-1]:g} m)")
    if zero_start:
        zl, zr = zl - zl[0], zr - zr[0]
    return SampledRoad(x=x, z_left=zl, z_right=zr, speed=speed,
                       length=float(x[-1]) if length is None else length,
                       name=f"mdf4:{Path(path).name}")
