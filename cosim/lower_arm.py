"""The lower suspension arm (front lower wishbone of the MPV): the one definition of its
hardpoints, its placement in the corner and its shape, read by the plant (multi-body model)
and by the fatigue worker (FE model). Metres, kilograms.

**Arm frame**: origin at the midpoint between the two body-bush centres, x along the pivot
(bush) axis pointing forward, y from the pivot axis outward toward the ball joint in the arm
plane, z = x × y (up). At static ride height the arm frame is parallel to the corner frame
(vehicle axes, origin at the static wheel centre of the front-left corner), offset by
:data:`ARM_ORIGIN`.

**The hardpoints are data**: the built-in corner file ``cosim/corners/mpv_front.toml``
(:mod:`cosim.corner`, docs/corners.md) gives them in the corner frame; this module puts them
in the arm frame (:func:`hardpoints_of`, :func:`arm_frame_of`: the same for a user's corner
file). The shape below (eyes, ribs, hole) is the part's, drawn round the built-in points.

**Where the numbers come from** (the thesis gives no drawing of its arm: Ch 6.2 approximated
it from a half-scale physical model; Table 4.2 gives its MBS mass, 5 kg, and the suspension's
torsional stiffness K_θ = 46.74 N m/deg):

* *ball-joint lever* ``BALL_JOINT[1]`` = 0.294 m. The torsion bar acts about the pivot axis, so
  the wheel rate is k_s ≈ K_θ / L² (the wheel centre follows the ball joint vertically; the
  upright's rotation is small). Table 4.3's k_s = 31 000 N/m with K_θ = 2678 N m/rad needs
  L = sqrt(2678 / 31 000) = 0.294 m (Ch 4 extraction §2). Checked against the log-decrement
  equivalent lumped model (``suscosim equivalent-lumped``; tests/vehicles).
* *damper seat* ``DAMPER_MOUNT[1]`` = 0.185 m: the damper (3800 N s/m, Table 4.2) acts as the
  lumped c_s = 1500 N s/m (Table 4.3) through a motion ratio MR = sqrt(1500 / 3800) = 0.628,
  i.e. 0.628 × 0.294 = 0.185 m from the pivot axis (cos² of the 4° damper lean: -0.5 %).
* *bush spacing* 0.26 m (0.25-0.35 m on small-MPV and C-segment front wishbones); the ball
  joint 25 mm ahead of the bush midpoint (a longer rear leg that takes the braking load). The
  spacing does not enter the wheel rate; it sets how the bushes share the ball-joint load.
* *torsion spring*: Table 4.2's K_θ acts about the pivot axis, between body and arm. Its
  moment M_x enters the arm through its pivot, **half at each bush eye**: the thesis's FE split
  the body revolute joint's loads equally between its two nodes A and B (Ch 6.2, Fig 6.7); a
  torsion bar splined into a pivot shaft through both eyes does the same.
* *damper seat* on the front leg's centre line (x = 0.064 m at y = 0.185 m) and *bump-stop
  pad* on the rear leg's centre line 0.215 m outboard (the jounce bumper on the body strikes
  it; :mod:`nodes.plant.bump_stop` gives its clearance and rate): both on a leg, so the
  lightening hole can reach toward the ball joint.

**Shape**: the part file ``nodes/fatigue/parts/data/lower_arm.toml`` (the parametric CAD of
``lower_arm_cad.toml``, docs/parts.md), whose joint centres are these hardpoints.
"""

from __future__ import annotations

from typing import TypedDict

import numpy as np

from . import corner as corner_file
from .corner import Corner


def arm_frame_of(c: Corner) -> tuple[np.ndarray, np.ndarray]:
    """(origin, R) of a corner's lower-arm frame in its corner frame at static ride height:
    origin the bush midpoint, columns of R the arm's x (rear bush -> front bush), y (toward the
    ball joint, normal to x) and z = x cross y; p_arm = R.T @ (p_corner - origin) [m]."""
    f, r, bj = c.points["lower_bush_front"], c.points["lower_bush_rear"], \
        c.points["lower_ball_joint"]
    o = 0.5 * (f + r)
    ex = f - r
    ex /= np.linalg.norm(ex)
    d = bj - o
    ey = d - ex * (d @ ex)
    ey /= np.linalg.norm(ey)
    return o, np.column_stack([ex, ey, np.cross(ex, ey)])


def hardpoints_of(c: Corner) -> dict[str, np.ndarray]:
    """A corner's lower-arm load points in its arm frame [m] (:data:`HARDPOINTS`' names)."""
    o, R = arm_frame_of(c)
    names = {"bush_front": "lower_bush_front", "bush_rear": "lower_bush_rear",
             "ball_joint": "lower_ball_joint", "damper_mount": "damper_lower",
             "bump_stop": "bump_stop_pad"}
    out: dict[str, np.ndarray] = {}
    for name, key in names.items():
        if key in c.points:
            out[name] = R.T @ (c.points[key] - o)
    return out


_CORNER = corner_file.builtin()
_O, _R = arm_frame_of(_CORNER)
_HP = hardpoints_of(_CORNER)
BUSH_FRONT = _HP["bush_front"]
BUSH_REAR = _HP["bush_rear"]
BALL_JOINT = _HP["ball_joint"]
DAMPER_MOUNT = _HP["damper_mount"]
BUMP_STOP_PAD = _HP["bump_stop"]
TORSION_SPRING_POINTS = (BUSH_FRONT, BUSH_REAR)
"""Where the torsion spring's moment M_x enters the arm: half at each bush eye [m]."""

HARDPOINTS: dict[str, np.ndarray] = {
    "bush_front": BUSH_FRONT,
    "bush_rear": BUSH_REAR,
    "ball_joint": BALL_JOINT,
    "damper_mount": DAMPER_MOUNT,
    "bump_stop": BUMP_STOP_PAD,
}
"""Load points of the arm (arm frame, m): the built-in corner's."""

ARM_ORIGIN = _O
"""Arm-frame origin (bush midpoint) in the corner frame [m]: the ball joint sits 60 mm inboard
of and 130 mm below the wheel centre (inside the wheel rim)."""
ARM_ROTATION = _R
"""The arm frame's axes in the corner frame at static ride height (columns x, y, z); the
identity for the built-in corner (arm frame parallel to the corner frame)."""

MASS_KG = 5.0
"""Table 4.2's lower-arm mass [kg] (the plant's lower-arm mass; the FE arm's is within 10 %,
tested)."""

class MassProperties(TypedDict):
    """The arm's mass [kg], centre of mass (arm frame) [m] and inertia tensor [kg m^2]."""

    mass_kg: float
    centre_of_mass_m: tuple[float, float, float]
    inertia_kg_m2: tuple[tuple[float, float, float], ...]


MASS_PROPERTIES: MassProperties = {
    "mass_kg": 5.446,
    "centre_of_mass_m": (0.0068, 0.0850, 0.0),
    "inertia_kg_m2": ((0.0547, -0.0034, 0.0), (-0.0034, 0.0516, 0.0), (0.0, 0.0, 0.1050)),
}
"""The lower arm's mass, centre of mass (arm frame) and inertia tensor about it (arm axes),
as the plant's rigid lower arm takes them (the inertia scaled to its Table 4.2 mass). Source:
the hand-meshed forged arm's 15 mm mesh, recomputed by the test oracle
tests/fatigue/oracle_hex_arm.py (the CAD arm's differ: CHANGELOG.md 2026-12-06)."""


def to_corner(point_arm: np.ndarray) -> np.ndarray:
    """An arm-frame point in the static corner frame [m]: origin + R @ p (for the built-in
    corner R is the identity, whose product gives p's own bits)."""
    corner: np.ndarray = ARM_ORIGIN + ARM_ROTATION @ np.asarray(point_arm, dtype=float)
    return corner


def lever_ball_joint() -> float:
    """Horizontal distance of the ball joint from the pivot axis, L [m]."""
    return float(BALL_JOINT[1])
