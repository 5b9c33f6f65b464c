"""A double-wishbone corner as data: the reader of a corner file (``suscosim-corner``, v1).

A corner file (TOML; docs/corners.md) holds the **left** corner's hardpoints in vehicle axes
(ISO 8855: x forward, y left, z up; metres), part masses, spring (torsion bar about the lower
arm's pivot axis and/or coil spring), nominal damper, jounce bumper and body bushes.

Every point is returned in the **corner frame**: vehicle axes, origin at the static wheel
centre. With ``frame.reference = "wheel_centre"`` the file's numbers are used as they are;
with ``"vehicle"`` the file's ``wheel_centre`` is subtracted and the half track is its y. Bad
input raises :class:`cosim.errors.InputFileError` naming the file and the key.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from .config import ConfigReader
from .errors import InputFileError, ScenarioError
from .safe_open import read_user_toml

FORMAT = "suscosim-corner"
VERSION = 1
BUILTIN = Path(__file__).with_name("corners") / "mpv_front.toml"
"""The built-in corner (the thesis's MPV front-left corner)."""

POINTS = ("lower_bush_front", "lower_bush_rear", "lower_ball_joint", "upper_bush_front",
          "upper_bush_rear", "upper_ball_joint", "tie_rod_inner", "tie_rod_outer",
          "damper_lower", "damper_upper")
"""Hardpoints every corner gives [m]."""
OPTIONAL_POINTS = ("bump_stop_pad", "spring_lower", "spring_upper", "wheel_centre")
"""Hardpoints a corner gives when it has the part (bump stop, coil spring) or the frame
(``wheel_centre`` with ``reference = "vehicle"``)."""
BUSHES = ("lower_front", "lower_rear", "upper_front", "upper_rear")
MASSES = ("body", "hub", "lower_arm", "upper_arm", "tie_rod")


@dataclass(frozen=True)
class Bush:
    """A body bush's stiffness: radial (normal to the pivot axis) and axial [N/m]."""

    radial: float
    axial: float


@dataclass(frozen=True)
class Corner:
    """A corner file, read and checked. Points in the corner frame [m] (module docstring)."""

    name: str
    source: str  # the path it was read from
    points: dict[str, np.ndarray]
    half_track: float  # wheel centre from the vehicle centreline [m]
    tyre_loaded_radius: float  # static wheel centre height above the ground [m]
    masses: dict[str, float]
    """body, hub, lower_arm, upper_arm, tie_rod [kg]; ``wheel`` (the spinning part of the
    hub: wheel, tyre, disc) when the file gives it."""
    torsion_bar_nm_per_deg: float  # K_theta about the lower arm's pivot axis (0: none)
    coil_n_per_m: float  # coil rate between spring_lower and spring_upper (0: none)
    damper_c_nominal: float  # along its axis [N s/m] (the check's equivalent quarter car)
    bump_stop: dict[str, float] | None
    """clearance [m], initial_rate [N/m], stroke [m], transition [-]; None: no bumper."""
    bushes: dict[str, Bush] = field(default_factory=dict)
    description: str = ""

    def point(self, name: str) -> np.ndarray:  # a copy [m]
        return self.points[name].copy()

    def mirrored(self) -> Corner:
        """The right-hand corner: every point mirrored, (x, y, z) -> (x, -y, z). Its lower-arm
        frame (:func:`cosim.lower_arm.arm_frame_of`: x forward, y outboard, so z down) is the
        left arm's mirrored: the arm's points and loads in it are the left part's."""
        m = np.array([1.0, -1.0, 1.0])
        return replace(self, points={k: v * m for k, v in self.points.items()},
                       name=f"{self.name} (mirrored)")


def _err(path: str, exc: ScenarioError) -> InputFileError:
    return InputFileError(path, f"key '{exc.key}': got {exc.value!r}, expected {exc.expected}")


def load(path: str | Path, key: str = "vehicle.corner") -> Corner:
    """Read and check a corner file (``key``: the scenario key that names it)."""
    p = Path(path)
    data = read_user_toml(p, "corner", key)
    try:
        return from_dict(data, str(p))
    except ScenarioError as exc:
        raise _err(str(p), exc) from None


MAX_COORDINATE_M = 10.0
"""Largest hardpoint coordinate or half track [m]: a corner's points are within ~1 m of its
wheel; more is millimetres, or not a number a model can take."""


def _vec(r: ConfigReader, name: str) -> np.ndarray:
    v = np.array(r.number_list(name, length=3, expected="[x, y, z] in metres"))
    if not np.all(np.abs(v) <= MAX_COORDINATE_M):
        raise r.error(name, v.tolist(), f"[x, y, z] in metres, each within "
                                        f"+-{MAX_COORDINATE_M:g} m (millimetres?)")
    return v


def from_dict(data: dict[str, Any], source: str = "<corner>") -> Corner:
    """A :class:`Corner` from a parsed corner file; bad keys raise ScenarioError (key named)."""
    top = ConfigReader(data, "", ("format", "version", "name", "description", "frame",
                                  "hardpoints", "masses", "spring", "damper", "bump_stop",
                                  "bushes"))
    top.choice("format", (FORMAT,))
    top.integer("version", lo=VERSION, hi=VERSION)
    name = top.string("name")
    description = top.string("description", "", empty=True)
    fr = top.section("frame", ("reference", "half_track", "tyre_loaded_radius"))
    reference = fr.choice("reference", ("wheel_centre", "vehicle"))
    hp = top.section("hardpoints", (*POINTS, *OPTIONAL_POINTS))
    raw = {n: _vec(hp, n) for n in (*POINTS, *OPTIONAL_POINTS) if n in POINTS or hp.has(n)}
    if reference == "vehicle":
        if "wheel_centre" not in raw:
            raise hp.error("wheel_centre", None, "the static wheel centre (reference = "
                           "'vehicle' measures the points from the vehicle's origin)")
        if fr.has("half_track"):
            raise fr.error("half_track", fr.value("half_track"),
                           "no half_track with reference = 'vehicle' (it is wheel_centre's y)")
        wc = raw.pop("wheel_centre")
        points = {n: v - wc for n, v in raw.items()}
        half_track = float(wc[1])
        if not half_track > 0:
            raise hp.error("wheel_centre", wc.tolist(), "a left corner: y > 0 (ISO 8855)")
    else:
        if "wheel_centre" in raw and np.any(raw["wheel_centre"] != 0.0):
            raise hp.error("wheel_centre", raw["wheel_centre"].tolist(),
                           "[0, 0, 0] or absent with reference = 'wheel_centre'")
        raw.pop("wheel_centre", None)
        points = raw
        half_track = fr.number("half_track", positive=True, hi=MAX_COORDINATE_M, unit="m")
    radius = fr.number("tyre_loaded_radius", 0.30, positive=True, unit="m")
    ms = top.section("masses", (*MASSES, "wheel"))
    masses = {n: ms.number(n, positive=True, unit="kg") for n in MASSES}
    if ms.has("wheel"):  # the spinning part of the hub's mass (the full vehicle's wheel)
        masses["wheel"] = ms.number("wheel", lo=0.0, hi=masses["hub"], lo_open=True,
                                    hi_open=True, unit="kg (part of masses.hub)")
    sp = top.section("spring", ("torsion_bar_nm_per_deg", "coil_n_per_m"))
    k_theta = sp.number("torsion_bar_nm_per_deg", 0.0, lo=0.0, unit="N m/deg")
    k_coil = sp.number("coil_n_per_m", 0.0, lo=0.0, unit="N/m")
    if k_theta == 0.0 and k_coil == 0.0:
        raise sp.error("torsion_bar_nm_per_deg", 0.0, "a torsion bar or a coil spring > 0")
    if k_coil > 0.0:
        for n in ("spring_lower", "spring_upper"):
            if n not in points:
                raise hp.error(n, None, "the coil spring's mount (coil_n_per_m > 0)")
    dm = top.section("damper", ("c_nominal",))
    c_nom = dm.number("c_nominal", lo=0.0, unit="N s/m")
    bs = top.section("bump_stop", ("enabled", "clearance", "initial_rate", "stroke",
                                   "transition"))
    bump: dict[str, float] | None = None
    if bs.boolean("enabled", False):
        bump = {"clearance": bs.number("clearance", positive=True, unit="m"),
                "initial_rate": bs.number("initial_rate", positive=True, unit="N/m"),
                "stroke": bs.number("stroke", positive=True, unit="m"),
                "transition": bs.number("transition", 0.9, lo=0.0, hi=1.0, lo_open=True,
                                        hi_open=True)}
        if "bump_stop_pad" not in points:
            raise hp.error("bump_stop_pad", None, "the bumper's pad on the lower arm "
                           "(bump_stop.enabled = true)")
    bu = top.section("bushes", BUSHES)
    bushes = {}
    for n in BUSHES:
        if bu.has(n):
            b = bu.section(n, ("radial", "axial"))
            bushes[n] = Bush(b.number("radial", positive=True, unit="N/m"),
                             b.number("axial", positive=True, unit="N/m"))
    corner = Corner(name=name, source=source, points=points, half_track=half_track,
                    tyre_loaded_radius=radius, masses=masses, torsion_bar_nm_per_deg=k_theta,
                    coil_n_per_m=k_coil, damper_c_nominal=c_nom, bump_stop=bump,
                    bushes=bushes, description=description)
    check_geometry(corner, hp)
    return corner


def check_geometry(c: Corner, hp: ConfigReader) -> None:
    """Refuse geometry no double wishbone has: coincident bushes, a ball joint on its arm's
    pivot axis, a right-hand corner, a zero-length link."""
    P = c.points
    for arm in ("lower", "upper"):
        f, r, bj = P[f"{arm}_bush_front"], P[f"{arm}_bush_rear"], P[f"{arm}_ball_joint"]
        axis = f - r
        if not np.linalg.norm(axis) > 1e-3:
            raise hp.error(f"{arm}_bush_front", f.tolist(),
                           f"a point >= 1 mm from {arm}_bush_rear (the pivot axis)")
        lever = np.linalg.norm(np.cross(axis / np.linalg.norm(axis), bj - r))
        if not lever > 0.02:
            raise hp.error(f"{arm}_ball_joint", bj.tolist(),
                           f"a point >= 20 mm from the {arm} arm's pivot axis")
        if not bj[1] > 0.5 * (f[1] + r[1]):
            raise hp.error(f"{arm}_ball_joint", bj.tolist(),
                           "outboard of its bushes (y larger: the file is the LEFT corner)")
    for a, b in (("lower_ball_joint", "upper_ball_joint"), ("tie_rod_inner", "tie_rod_outer"),
                 ("damper_lower", "damper_upper")):
        if not np.linalg.norm(P[a] - P[b]) > 1e-3:
            raise hp.error(b, P[b].tolist(), f"a point >= 1 mm from {a}")
    if c.coil_n_per_m > 0 and not np.linalg.norm(P["spring_upper"] - P["spring_lower"]) > 1e-3:
        raise hp.error("spring_upper", P["spring_upper"].tolist(),
                       "a point >= 1 mm from spring_lower")
    if not math.isfinite(c.half_track):
        raise hp.error("wheel_centre", c.half_track, "a finite half track")


_builtin: Corner | None = None


def builtin() -> Corner:
    """The built-in corner, read once."""
    global _builtin
    if _builtin is None:
        _builtin = load(BUILTIN)
    return _builtin
