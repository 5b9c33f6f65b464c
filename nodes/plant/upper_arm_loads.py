"""The loads ON the upper arm of the double-wishbone corner (:mod:`.double_wishbone`): the
``upper_arm`` channel, read from PyBullet's pivot joint sensor and the upper ball joint's
point-to-point constraint.

**Upper-arm frame** (the lower arm's rule, :func:`cosim.lower_arm.arm_frame_of`, applied to
the corner's upper points): origin at the midpoint of the two upper bush centres
(``upper_bush_front``, ``upper_bush_rear`` of the corner file), x along the pivot axis from the
rear bush to the front one, y from the pivot axis toward the upper ball joint
(``upper_ball_joint``) normal to x, z = x cross y; it turns with the arm. For the built-in
corner the arm is inclined 4.8 deg (its inner end 20 mm below its outer end), so its y and z
are the corner's turned by that much about x. The points come from the corner file only
(:func:`upper_arm_corner`: the corner with its lower-arm point names carrying the upper
arm's points, read by the same functions): one definition of each hardpoint.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from cosim import lower_arm as la
from cosim.corner import Corner

from .arm_loads import bush_split
from .double_wishbone_geometry import UPPER_ARM
from .point_kinematics import to_frame
from .quiet_pybullet import p

if TYPE_CHECKING:
    from .double_wishbone import DoubleWishboneCorner

UPPER_POINTS = {"bush_front": "upper_bush_front", "bush_rear": "upper_bush_rear",
                "ball_joint": "upper_ball_joint"}
"""The arm-frame point names of :func:`cosim.lower_arm.hardpoints_of` -> the corner file's
upper-arm points."""
FIELDS = tuple(f"{UPPER_POINTS[k]}_{ax}" for k in ("ball_joint", "bush_front", "bush_rear")
               for ax in "xyz")
"""The ``plant/upper_arm`` fields, in order (:mod:`cosim.schema`)."""


def upper_arm_corner(c: Corner) -> Corner:
    """``c`` with only the lower-arm point names, each carrying the upper arm's point, so that
    :func:`cosim.lower_arm.arm_frame_of` and :func:`~cosim.lower_arm.hardpoints_of` give the
    upper arm's frame and points."""
    pts = {f"lower_{k}": c.points[v] for k, v in UPPER_POINTS.items()}
    return replace(c, points=pts)


def upper_arm_frame(c: Corner) -> tuple[np.ndarray, np.ndarray]:
    """(origin, R) of the upper-arm frame in the corner frame at static ride height (columns
    of R: its x, y, z); p_frame = R.T @ (p_corner - origin) [m]."""
    return la.arm_frame_of(upper_arm_corner(c))


def upper_hardpoints(c: Corner) -> dict[str, np.ndarray]:
    """The upper arm's load points in its frame, by the corner file's names
    (``upper_ball_joint``, ``upper_bush_front``, ``upper_bush_rear``) [m]."""
    hp = la.hardpoints_of(upper_arm_corner(c))
    return {UPPER_POINTS[k]: v for k, v in hp.items()}


def upper_arm_loads_later(model: DoubleWishboneCorner) -> Callable[[], dict[str, float]]:
    """Loads ON the upper arm during the latest substep, in the upper-arm frame at the start
    of that substep, t_k [N]:

    * ``upper_ball_joint_{x,y,z}``: the force from the hub at the upper ball joint: minus the
      force the POINT2POINT constraint (parent upper arm, child hub) applies on the hub
      (``getConstraintState``: world axes);
    * ``upper_bush_front_{x,y,z}``, ``upper_bush_rear_{x,y,z}``: the forces from the body at
      the two bush centres, from the pivot's joint sensor (the body's wrench on the arm, link
      axes, about the arm's centre of mass) moved to the frame origin and split between the
      bushes by the moments about y and z (as the lower arm's, :func:`.arm_loads.
      arm_loads_at`); the axial force shared equally. The moment about the pivot axis is 0
      (a free revolute joint: no spring on the upper arm).

    With the arm's weight they balance its inertia: sum F + m g = m a_com and the moments
    (tested in tests/vehicles/test_double_wishbone.py). As a function to call later:
    PyBullet's sensors are read now (before the next substep), the arithmetic at the call."""
    c, b = model.client, model.body
    w = p.getJointState(b, UPPER_ARM, physicsClientId=c)[2]
    h = p.getConstraintState(model._c_upper, physicsClientId=c)  # on the hub, world axes
    rows, r_com, d = model._ua_frame_rows, model._ua_r_com, model._ua_spacing
    quat = model._ua_quat_applied  # the arm link's rotation at the start of the substep

    def loads() -> dict[str, float]:
        _M0, front, rear = bush_split(w, r_com, rows, d)
        ball = to_frame(rows, p.getMatrixFromQuaternion(quat), (-h[0], -h[1], -h[2]))
        out: dict[str, float] = {}
        for i, f in enumerate((ball, front, rear)):
            out[FIELDS[3 * i]], out[FIELDS[3 * i + 1]], out[FIELDS[3 * i + 2]] = f
        return out

    return loads
