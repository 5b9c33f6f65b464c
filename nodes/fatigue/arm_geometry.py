"""Hardpoints and outline of the default lower suspension arm (an MPV lower wishbone).

Arm frame (shared with the plant): origin at the midpoint between the two body-bush centres,
x along the pivot (bush) axis pointing forward, y from the pivot axis outward toward the ball
joint in the arm plane, z = x × y (up). Metres.

Source/reasoning: the thesis gives no drawing of its arm (it was approximated from a half-scale
physical model; Ch 6.2) and only its MBS mass, 5 kg (Table 4.2). The numbers below are chosen
for a typical front lower wishbone of a mid-size MPV: bush spacing 0.32 m (0.30-0.35 m typical),
ball joint 0.37 m outboard of the pivot axis and slightly forward of the bush midpoint (an
A-arm with a longer rear leg), spring/damper seat on the arm 0.225 m outboard, all in the arm's
mid-plane (z = 0). The arm is a flat steel plate, 14 mm thick, whose outline is the convex hull
of circular bosses round the three joints, with a rounded triangular lightening hole whose
outboard corner is the notch where the stress concentrates (the thesis's critical node 217 was
"near the notch", bottom surface). Its mass is 8.8 kg, more than the thesis's 5 kg MBS arm: a
flat plate needs more steel than a flanged pressing for the same stiffness; its first flexible
mode (≈ 365 Hz) is close to the thesis's 362 Hz.
"""

from __future__ import annotations

import numpy as np

BUSH_FRONT = np.array([0.160, 0.0, 0.0])
BUSH_REAR = np.array([-0.160, 0.0, 0.0])
BALL_JOINT = np.array([0.030, 0.370, 0.0])
DAMPER_MOUNT = np.array([0.020, 0.225, 0.0])

HARDPOINTS = {
    "bush_front": BUSH_FRONT,
    "bush_rear": BUSH_REAR,
    "ball_joint": BALL_JOINT,
    "damper_mount": DAMPER_MOUNT,
}

#: plate thickness (m), arm mid-plane at z = 0
PLATE_THICKNESS = 0.014
#: boss radii round the joints (m): outline = convex hull of these circles
BUSH_BOSS_RADIUS = 0.032
BALL_JOINT_BOSS_RADIUS = 0.036
#: lightening hole: rounded triangle, corner centres (x, y) and fillet radius (m)
HOLE_CORNERS = np.array([[0.090, 0.048], [-0.095, 0.048], [0.012, 0.165]])
HOLE_FILLET_RADIUS = 0.016
#: radius (m, in the arm plane) of the node patches that carry a joint's load / support
LOAD_PATCH_RADIUS = 0.020
SUPPORT_PATCH_RADIUS = 0.020


def geometry_key() -> dict[str, object]:
    """Every number that defines the default arm (used in the FE cache key)."""
    return {
        "hardpoints": {k: v.tolist() for k, v in HARDPOINTS.items()},
        "thickness": PLATE_THICKNESS,
        "bush_boss": BUSH_BOSS_RADIUS,
        "bj_boss": BALL_JOINT_BOSS_RADIUS,
        "hole": HOLE_CORNERS.tolist(),
        "hole_r": HOLE_FILLET_RADIUS,
        "load_patch": LOAD_PATCH_RADIUS,
        "support_patch": SUPPORT_PATCH_RADIUS,
    }
