"""The loads ON the lower arm of the double-wishbone corner (:mod:`.double_wishbone`), read
from PyBullet's joint sensors and the forces the corner applied (the ``arm`` channel)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from .double_wishbone_geometry import HUB
from .point_kinematics import cross3, to_frame, transpose_times
from .quiet_pybullet import p

if TYPE_CHECKING:
    from .double_wishbone import DoubleWishboneCorner


def arm_loads(model: DoubleWishboneCorner) -> dict[str, float]:
    """Loads ON the lower arm during the latest substep, in the arm frame at the start of that
    substep, t_k [N, N m] (:func:`cosim.lower_arm.arm_frame_of`: origin at the bush midpoint, x
    along the pivot axis forward, y toward the ball joint, z = x cross y; it turns with the
    arm); where each acts: the arm-frame points of :data:`cosim.lower_arm.HARDPOINTS`.

    * ``ball_joint_{x,y,z}``: from the hub: minus the lower ball joint's sensor force
      (parent arm -> child hub), from the hub frame;
    * ``damper_mount_{x,y,z}``: from the damper at its seat, -F_d along the damper axis;
    * ``bush_front_{x,y,z}``, ``bush_rear_{x,y,z}``: from the body: the pivot's sensor wrench
      (body -> arm) moved to the frame origin, F and M_O = M_com + r_com x F, split by the
      moments between the bushes at x = +-d/2: F_front,z = F_z/2 - M_y/d, F_rear,z = F_z/2 +
      M_y/d, F_front,y = F_y/2 + M_z/d, F_rear,y = F_y/2 - M_z/d, the axial F_x shared
      equally (statically indeterminate between two bushes of equal stiffness);
    * ``bump_stop_y``, ``bump_stop_z``: from the bumper at the pad, (0, 0, -F_bs) in world
      axes: -F_bs sin(theta) and -F_bs cos(theta) <= 0 for an arm turned by theta (jounce
      positive; no x component: the arm turns about x, the body only heaves); 0 while clear;
    * ``torsion_bar_mx`` [N m]: the torsion spring's moment about x (M_x of the pivot, static
      preload included), a pure moment entering through the pivot, half at each bush eye
      (:data:`cosim.lower_arm.TORSION_SPRING_POINTS`, as the thesis split its revolute
      joint's loads over nodes A and B): for the rigid arm its point does not matter, for the
      FE it does.

    PyBullet's joint force-torque sensor (``getJointState(...)[2]``, ``getJointStateMultiDof``
    for spherical joints) gives the wrench the **parent exerts on the child**, in the **child
    link frame**, about the child's **centre of mass**, the joint motor torque and the loop
    constraints' forces included. That frame is the one at the **start** of the substep
    (where its forces are evaluated), so the loads are rotated with the pose at t_k (the pose
    after would misplace them by omega dt). With the arm's weight they balance its inertia:
    sum F + m g = m a_com, sum (r x F) + M_x e_x = dH/dt (tests/vehicles/test_double_wishbone.py,
    static and in bumper contact).
    """
    return arm_loads_later(model)()


def arm_loads_later(model: DoubleWishboneCorner) -> Callable[[], dict[str, float]]:
    """:func:`arm_loads` with PyBullet's sensors read now (before the next substep) and the
    arithmetic left to the call of the function returned."""
    args = (model._w_pivot,
            p.getJointStateMultiDof(model.body, HUB, physicsClientId=model.client)[2],
            model.geom.arm_rotation, model._applied_pose, model._arm_r_com,
            model._F_d, (0.0, 0.0, -model._F_bs), model.geom.bush_spacing)
    return lambda: arm_loads_at(*args)


def bush_split(w: Sequence[float], r_com: Sequence[float], R_f: Sequence[Sequence[float]],
               d: float
               ) -> tuple[float, tuple[float, float, float], tuple[float, float, float]]:
    """(M_x, front bush force, rear bush force) in an arm frame with axes ``R_f`` (in the
    link frame, by rows) from a pivot sensor wrench ``w`` (about the centre of mass ``r_com``
    [m]): moved to the frame origin, split between bushes ``d`` [m] apart (:func:`arm_loads`).
    Floats, the bits of the numpy expressions (:mod:`.point_kinematics`)."""
    rxF = cross3(r_com, w[:3])
    M_link = [w[3] + rxF[0], w[4] + rxF[1], w[5] + rxF[2]]  # about the link origin = O
    F0, F1, F2 = transpose_times(R_f, w[:3])
    M0, M1, M2 = transpose_times(R_f, M_link)
    return (M0, (F0 / 2, F1 / 2 + M2 / d, F2 / 2 - M1 / d),
            (F0 / 2, F1 / 2 - M2 / d, F2 / 2 + M1 / d))


def arm_loads_at(w_pivot: Sequence[float], w_hub: Sequence[float], R_af: np.ndarray,
                 applied_pose: tuple, r_com: Sequence[float], F_d_axial: float,
                 bump_on_arm: Sequence[float], d: float) -> dict[str, float]:
    """:func:`arm_loads` of one corner of any model, from the lower-arm pivot's and the ball
    joint's sensor wrenches (``getJointState(..)[2]``, ``getJointStateMultiDof(..)[2]``), the
    arm frame's axes in the arm link's frame ``R_af``, the pose the substep's forces were
    applied in (the arm link's world rotation, the hub's world quaternion, the damper's unit
    vector arm -> body), the arm's centre of mass in its link frame [m], the damper's axial
    force F_d [N] (compression-positive on the body), the bumper's force on the arm (world
    vector) [N] and the bush spacing d [m]. Floats (:mod:`.point_kinematics`)."""
    R_arm, hub_quat, u = applied_pose  # the pose at the start of the substep
    R_f, R_link = R_af.tolist(), R_arm.ravel().tolist()
    M0, front, rear = bush_split(w_pivot, r_com, R_f, d)
    H = p.getMatrixFromQuaternion(hub_quat)  # the hub's rotation, row-major
    w0, w1, w2 = w_hub[0], w_hub[1], w_hub[2]
    on_arm = [-(H[0] * w0 + H[1] * w1 + H[2] * w2), -(H[3] * w0 + H[4] * w1 + H[5] * w2),
              -(H[6] * w0 + H[7] * w1 + H[8] * w2)]  # minus the hub's, in world axes
    F_d = -F_d_axial
    ball = to_frame(R_f, R_link, on_arm)
    damper = to_frame(R_f, R_link, (F_d * u[0], F_d * u[1], F_d * u[2]))
    bump = to_frame(R_f, R_link, bump_on_arm)
    out: dict[str, float] = {}
    for names, f in ((_BALL, ball), (_DAMPER, damper), (_FRONT, front), (_REAR, rear)):
        out[names[0]], out[names[1]], out[names[2]] = f
    out["bump_stop_y"] = bump[1]
    out["bump_stop_z"] = bump[2]
    out["torsion_bar_mx"] = M0
    return out


_BALL, _DAMPER, _FRONT, _REAR = (tuple(f"{name}_{axis}" for axis in "xyz") for name in
                                 ("ball_joint", "damper_mount", "bush_front", "bush_rear"))
