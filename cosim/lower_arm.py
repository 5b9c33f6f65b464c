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

**Shape**: a forged H-section wishbone in 817M40, the thesis's Table 6.2 steel, quenched and
tempered (why forged and not a pressed HSLA shell: the torsion spring's static moment, 1.56 kN m
at the static wheel load, passes through the legs' roots; a 3 mm S420 double shell of 5 kg
would reach its yield strength under a 3 g bump, the 1166 MPa Q&T steel does not). In plan: a
triangle (convex hull of round bosses at the three joints) with a rounded triangular lightening
hole, so two legs and a base member between the eyes. In section (z, symmetric about z = 0): a
thin horizontal **web**, deep vertical **ribs** along the outer edge and round the hole (the H's
flanges; forged control arms have this pocketed section), deepest at the legs' roots by the eyes
and tapering toward the ball joint with the bending moment, shallower on the base member, and
deep **hubs** at the bush eyes (their axis is x in reality; here a solid hub of the hollow
eye's mass), the ball joint, the damper seat and the bump-stop pad. :func:`rib_depth` and
:func:`boss_depth` are the depth field the FE mesh follows. Web 3 mm; ribs 5-6 mm wide, 54 mm
deep at the roots, 30 mm by the ball joint, 30 mm on the base; eyes 60 mm deep. The FE gives
5.33-5.45 kg (Table 4.2: 5 kg; 20 and 15 mm meshes) and a first free-free mode of 594 Hz
(Table 6.1: 362 Hz; the stiff sections are what carrying the torsion spring's moment takes,
docs/fatigue.md) (``suscosim arm``).
"""

from __future__ import annotations

import math
from typing import TypedDict

import numpy as np

from . import corner as corner_file
from .corner import Corner

# ------------------------------------------------------------------ hardpoints, arm frame [m]
# The points are the built-in corner file's (cosim/corners/mpv_front.toml, corner frame), put
# in the arm frame here: one definition of each hardpoint, read by the plant and by the FE.


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
    """A corner's lower-arm load points in its arm frame [m] (:data:`HARDPOINTS`' names; the
    bump-stop pad only if the corner has one)."""
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

# ------------------------------------------------------------------ shape (FE), arm frame [m]
BUSH_BOSS_RADIUS = 0.030
"""Radius of the bush eyes (in plan) [m]."""
BALL_JOINT_BOSS_RADIUS = 0.032
"""Radius of the ball-joint boss (in plan) [m]."""
HOLE_CORNERS = np.array([[0.079, 0.030], [-0.073, 0.030], [0.016, 0.192]])
"""Lightening hole: centres of its three rounded corners (x, y) [m]."""
HOLE_FILLET_RADIUS = 0.026
"""Corner radius of the lightening hole [m]."""

WEB_DEPTH = 0.003
"""Web thickness [m]."""
RIB_DEPTH = 0.054
"""Depth (z extent) of the legs' ribs at their root by the bush eyes [m]; they taper to
``RIB_DEPTH_TIP`` toward the ball joint, following the bending moment, which is largest at
the eyes where the torsion spring's moment enters."""
RIB_DEPTH_TIP = 0.030
"""Depth of the legs' ribs by the ball joint [m]."""
RIB_TAPER_Y = (0.05, 0.28)
"""The legs' rib depth tapers linearly between these distances y from the pivot axis [m]."""
BASE_RIB_DEPTH = 0.030
"""Depth of the ribs of the base member between the bush eyes [m]: it is a tie that carries
the bushes' axial and fore-aft forces, not the torsion-bar moment, so it is kept shallow."""
BASE_BLEND_Y = (0.03, 0.06)
"""The rib depth blends from the base's to the legs' between these distances y from the pivot
axis [m] ...)"""
BASE_BLEND_X = (0.05, 0.09)
"""... and between these distances |x| from the arm's middle [m] (the legs' roots at the eyes
keep their depth)."""
OUTER_RIB_WIDTH = 0.006
"""Width (in plan) of the rib along the outer edge [m]."""
HOLE_RIB_WIDTH = 0.005
"""Width (in plan) of the rib round the lightening hole [m]."""
BUSH_EYE_DEPTH = 0.060
"""Depth (z extent) of the bush eyes [m]."""
BALL_JOINT_BOSS_DEPTH = 0.036
"""Depth of the ball-joint boss [m]."""
SEAT_RADIUS = 0.012
"""Radius (in plan) of the flat pads at the damper seat and the bump-stop pad [m]."""
SEAT_DEPTH = 0.024
"""Depth of those pads [m] (the damper's clevis bolt and the bumper's strike plate)."""
EYE_CORE_RADIUS = 0.004
"""Radius out to which a bush eye / the ball-joint boss has its full depth [m]. The eyes are
modelled solid (the bush's steel sleeve and the joint's housing are stiff and carry the load
spider); the core radius is chosen so that the solid eye has the mass of the real hollow one
(outer diameter 60 mm, bore 44 mm for the bush): pi (0.030^2 - 0.022^2) = pi 0.0204^2."""
EYE_BLEND = 0.026
"""Radial blend of the bush eyes' hubs down to the web [m]: the torsion spring's moment enters
the arm through the eyes, and a thin web round an eye would carry it in plate bending."""
BOSS_BLEND = 0.008
"""Radial blend from a boss's depth down to the rib/web depth [m] (a forging draft/fillet)."""

LOAD_PATCH_RADIUS = 0.020
"""Radius (in plan) of the node patch over which a joint's load is spread [m]."""
JOINT_ZONE_MARGIN = 0.010
"""The joints' hubs plus this margin [m] are not assessed for fatigue (:func:`joint_zone_radius`):
there the FE stress is that of an idealised load introduction (a spider on a solid hub), not of
the real splined eye, ball-joint housing or bolted seat, which are assessed with their own
detailed models in practice (as the thesis's spider beams were not assessed)."""

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
"""The FE arm's mass, centre of mass (arm frame) and inertia tensor about it (arm axes), from
the 15 mm mesh (the 20 mm default gives 5.33 kg); the plant's rigid lower arm takes the
centre of mass and the inertia scaled to its Table 4.2 mass. Checked against the FE mesh in
tests/fatigue/test_arm_fe.py."""


def joint_zone_radius(name: str) -> float:
    """Radius in plan [m] round a hardpoint inside which nodes are not assessed."""
    if name.startswith("bush"):
        r = EYE_CORE_RADIUS + EYE_BLEND
    elif name == "ball_joint":
        r = EYE_CORE_RADIUS + BOSS_BLEND
    else:
        r = SEAT_RADIUS + BOSS_BLEND
    return max(r, LOAD_PATCH_RADIUS) + JOINT_ZONE_MARGIN


def to_corner(point_arm: np.ndarray) -> np.ndarray:
    """An arm-frame point in the static corner frame [m]: origin + R @ p (for the built-in
    corner R is the identity, whose product gives p's own bits)."""
    corner: np.ndarray = ARM_ORIGIN + ARM_ROTATION @ np.asarray(point_arm, dtype=float)
    return corner


def lever_ball_joint() -> float:
    """Horizontal distance of the ball joint from the pivot axis, L [m]."""
    return float(BALL_JOINT[1])


def motion_ratio_damper() -> float:
    """Damper seat lever / ball-joint lever (before the damper's lean) [-]."""
    return float(DAMPER_MOUNT[1] / BALL_JOINT[1])


def boss_depth(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Depth of the bosses (bush eyes, ball joint, damper seat, bump-stop pad) at plan points
    (x, y) [m]; 0 away from them."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    out = np.zeros(np.broadcast(x, y).shape)
    for c, r, h, blend in ((BUSH_FRONT, EYE_CORE_RADIUS, BUSH_EYE_DEPTH, EYE_BLEND),
                           (BUSH_REAR, EYE_CORE_RADIUS, BUSH_EYE_DEPTH, EYE_BLEND),
                           (BALL_JOINT, EYE_CORE_RADIUS, BALL_JOINT_BOSS_DEPTH, BOSS_BLEND),
                           (DAMPER_MOUNT, SEAT_RADIUS, SEAT_DEPTH, BOSS_BLEND),
                           (BUMP_STOP_PAD, SEAT_RADIUS, SEAT_DEPTH, BOSS_BLEND)):
        d = np.hypot(x - c[0], y - c[1])
        # full depth out to r, then a smooth (cosine) blend
        u = np.clip((d - r) / blend, 0.0, 1.0)
        out = np.maximum(out, h * 0.5 * (1.0 + np.cos(math.pi * u)))
    return out


def _smoothstep(v: np.ndarray, lo: float, hi: float) -> np.ndarray:
    u = np.clip((v - lo) / (hi - lo), 0.0, 1.0)
    step: np.ndarray = 0.5 * (1.0 - np.cos(math.pi * u))
    return step


def rib_depth(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Depth of the ribs at plan points (x, y) [m]: the legs' depth (deep at the eyes,
    tapering toward the ball joint), shallower on the base member between the eyes."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    w = np.maximum(_smoothstep(y, *BASE_BLEND_Y), _smoothstep(np.abs(x), *BASE_BLEND_X))
    v = np.clip((y - RIB_TAPER_Y[0]) / (RIB_TAPER_Y[1] - RIB_TAPER_Y[0]), 0.0, 1.0)
    leg = RIB_DEPTH + (RIB_DEPTH_TIP - RIB_DEPTH) * v
    depth: np.ndarray = BASE_RIB_DEPTH + (leg - BASE_RIB_DEPTH) * w
    return depth


def geometry_key() -> dict[str, object]:
    """Every number that defines the arm (FE cache key)."""
    names = ("BUSH_BOSS_RADIUS", "BALL_JOINT_BOSS_RADIUS", "HOLE_FILLET_RADIUS", "WEB_DEPTH",
             "RIB_DEPTH", "RIB_DEPTH_TIP", "RIB_TAPER_Y", "BASE_RIB_DEPTH", "BASE_BLEND_Y",
             "BASE_BLEND_X", "OUTER_RIB_WIDTH", "HOLE_RIB_WIDTH", "BUSH_EYE_DEPTH",
             "BALL_JOINT_BOSS_DEPTH", "SEAT_RADIUS", "SEAT_DEPTH", "EYE_CORE_RADIUS",
             "EYE_BLEND", "BOSS_BLEND", "LOAD_PATCH_RADIUS")
    key: dict[str, object] = {n: np.asarray(globals()[n]).tolist() for n in names}
    key["hardpoints"] = {k: v.tolist() for k, v in HARDPOINTS.items()}
    key["hole"] = HOLE_CORNERS.tolist()
    return key
