"""The lower suspension arm (front lower wishbone of the MPV): the one definition of its
hardpoints, its placement in the corner and its shape, read by the plant (multi-body model)
and by the fatigue worker (FE model). Metres, kilograms.

**Arm frame**: origin at the midpoint between the two body-bush centres, x along the pivot
(bush) axis pointing forward, y from the pivot axis outward toward the ball joint in the arm
plane, z = x × y (up). At static ride height the arm frame is parallel to the corner frame
(vehicle axes, origin at the static wheel centre of the front-left corner), offset by
:data:`ARM_ORIGIN`.

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
* *bush spacing* 0.30 m (0.28-0.35 m on small-MPV and C-segment front wishbones, e.g. the
  pressed and forged arms of the Ford Galaxy / VW Sharan class); the ball joint 25 mm ahead of
  the bush midpoint (a longer rear leg that takes the braking load).
* *torsion bar*: splined into the **front** bush eye (a longitudinal torsion bar running
  rearward to an anchor in the cross-member, as in torsion-bar front suspensions); the
  torsion-bar moment M_x enters the arm there.
* *bump-stop pad* on the arm's top face 0.215 m outboard (the jounce bumper on the body
  strikes it; :mod:`nodes.plant.bump_stop` gives its clearance and rate).

**Shape** (a forged I-section wishbone in 817M40, the thesis's Table 6.2 steel, quenched and
tempered; a pressed HSLA arm of the same mass would need a yield strength above its 3 g stress,
which a 3 mm S420 shell does not give with the torsion bar's moment entering at one eye): a
triangular plate outline (convex hull of round bosses at the three joints) with a lightening
hole, a thin horizontal **web** and deep vertical **ribs** along the outer edge and round the
hole (the flanges of the I), and deep **bosses** at the bush eyes and the ball joint. The
thickness field (z extent, symmetric about z = 0) is :func:`depth_at`; the FE mesh follows it.
Section dimensions are those of forged steel wishbones of this size: web 6 mm, ribs 10-12 mm
wide and 42 mm deep, bush eyes 56 mm long. They give 5.0 kg (Table 4.2: 5 kg) and a first
free-free mode near Table 6.1's 362 Hz (both checked by the FE: ``suscosim arm``).
"""

from __future__ import annotations

import math

import numpy as np

# ------------------------------------------------------------------ hardpoints, arm frame [m]
BUSH_FRONT = np.array([0.150, 0.0, 0.0])
BUSH_REAR = np.array([-0.150, 0.0, 0.0])
BALL_JOINT = np.array([0.025, 0.294, 0.0])
DAMPER_MOUNT = np.array([0.010, 0.185, 0.0])
BUMP_STOP_PAD = np.array([-0.030, 0.215, 0.0])
TORSION_BAR_SOCKET = BUSH_FRONT

HARDPOINTS: dict[str, np.ndarray] = {
    "bush_front": BUSH_FRONT,
    "bush_rear": BUSH_REAR,
    "ball_joint": BALL_JOINT,
    "damper_mount": DAMPER_MOUNT,
    "bump_stop": BUMP_STOP_PAD,
}
"""Load points of the arm (arm frame, m)."""

ARM_ORIGIN = np.array([0.0, -0.06 - 0.294, -0.13])
"""Arm-frame origin (bush midpoint) in the corner frame [m]: the ball joint sits 60 mm inboard
of and 130 mm below the wheel centre (inside the wheel rim)."""

MASS_KG = 5.0
"""Table 4.2's lower-arm mass [kg]; the FE arm's mass is within 10 % (tested)."""

# ------------------------------------------------------------------ shape (FE), arm frame [m]
BUSH_BOSS_RADIUS = 0.030
"""Radius of the bush eyes (in plan) [m]."""
BALL_JOINT_BOSS_RADIUS = 0.032
"""Radius of the ball-joint boss (in plan) [m]."""
HOLE_CORNERS = np.array([[0.085, 0.052], [-0.090, 0.052], [0.018, 0.170]])
"""Lightening hole: centres of its three rounded corners (x, y) [m]."""
HOLE_FILLET_RADIUS = 0.014
"""Corner radius of the lightening hole [m]."""

WEB_DEPTH = 0.006
"""Web thickness [m]."""
RIB_DEPTH = 0.042
"""Depth (z extent) of the ribs along the outer edge and round the hole [m]."""
OUTER_RIB_WIDTH = 0.012
"""Width (in plan) of the rib along the outer edge [m]."""
HOLE_RIB_WIDTH = 0.010
"""Width (in plan) of the rib round the lightening hole [m]."""
BUSH_EYE_DEPTH = 0.056
"""Depth (z extent) of the bush eyes [m]."""
BALL_JOINT_BOSS_DEPTH = 0.048
"""Depth of the ball-joint boss [m]."""
BOSS_BLEND = 0.012
"""Radial blend from a boss's depth down to the rib/web depth [m] (a forging draft/fillet)."""

LOAD_PATCH_RADIUS = 0.020
"""Radius (in plan) of the node patch over which a joint's load is spread [m]."""


def to_corner(point_arm: np.ndarray) -> np.ndarray:
    """An arm-frame point in the static corner frame [m] (the frames are parallel)."""
    return ARM_ORIGIN + np.asarray(point_arm, dtype=float)


def lever_ball_joint() -> float:
    """Horizontal distance of the ball joint from the pivot axis, L [m]."""
    return float(BALL_JOINT[1])


def motion_ratio_damper() -> float:
    """Damper seat lever / ball-joint lever (before the damper's lean) [-]."""
    return float(DAMPER_MOUNT[1] / BALL_JOINT[1])


def boss_depth(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Depth of the joint bosses at plan points (x, y) [m]; 0 away from the bosses."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    out = np.zeros(np.broadcast(x, y).shape)
    for c, r, h in ((BUSH_FRONT, BUSH_BOSS_RADIUS, BUSH_EYE_DEPTH),
                    (BUSH_REAR, BUSH_BOSS_RADIUS, BUSH_EYE_DEPTH),
                    (BALL_JOINT, BALL_JOINT_BOSS_RADIUS, BALL_JOINT_BOSS_DEPTH)):
        d = np.hypot(x - c[0], y - c[1])
        # full depth out to 0.75 r, then a smooth (cosine) blend over BOSS_BLEND
        u = np.clip((d - 0.75 * r) / BOSS_BLEND, 0.0, 1.0)
        out = np.maximum(out, h * 0.5 * (1.0 + np.cos(math.pi * u)))
    return out


def geometry_key() -> dict[str, object]:
    """Every number that defines the arm (FE cache key)."""
    return {
        "hardpoints": {k: v.tolist() for k, v in HARDPOINTS.items()},
        "bush_boss": BUSH_BOSS_RADIUS, "bj_boss": BALL_JOINT_BOSS_RADIUS,
        "hole": HOLE_CORNERS.tolist(), "hole_r": HOLE_FILLET_RADIUS,
        "web": WEB_DEPTH, "rib": RIB_DEPTH, "outer_rib_w": OUTER_RIB_WIDTH,
        "hole_rib_w": HOLE_RIB_WIDTH, "eye": BUSH_EYE_DEPTH, "bj_depth": BALL_JOINT_BOSS_DEPTH,
        "blend": BOSS_BLEND, "load_patch": LOAD_PATCH_RADIUS,
    }
