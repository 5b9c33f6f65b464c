"""The four-corner vehicle's wheels on a 3-D tyre and its driver's inputs:
the spinning wheel's mass and inertia, the contact frame and wheel kinematics the tyre/road
node takes, the road-plane tyre forces and the wheel torques and rack travel the plant
applies (a mixin of :class:`.full_vehicle_dw.FullVehicleDoubleWishbone`, which owns the
PyBullet world)."""

from __future__ import annotations

from typing import Any

import numpy as np

from cosim.corner import Corner

from .double_wishbone_geometry import CornerGeometry
from .quiet_pybullet import p

WHEEL_SHARE = 0.62
"""The spinning share of a corner's hub mass when its file gives no ``masses.wheel`` [-]: of
the MPV's 38.75 kg (Table 4.2), a 15-16 in steel wheel (8-9 kg), its tyre (8-9 kg), the brake
disc (5 kg) and the bearing's inner ring spin, about 24 kg (ours; the upright, calliper and
bearing housing the rest)."""
WHEEL_GYRATION = 0.205
"""Radius of gyration of the spinning wheel about its axis [m]: the tyre's mass at ~0.28 m,
the rim's at ~0.18 m, the disc's at ~0.1 m give I_spin ~ 1.0 kg m^2 for 24 kg (ours); its
diametral inertia is taken as 0.6 I_spin (a thin ring would have 0.5, a tyre's width adds)."""


def wheel_mass(c: Corner) -> float:
    """The spinning part of the corner's hub mass [kg] (``masses.wheel`` or
    :data:`WHEEL_SHARE` of ``masses.hub``)."""
    return c.masses.get("wheel", WHEEL_SHARE * c.masses["hub"])


def wheel_inertia(mass: float) -> tuple[float, float, float]:
    """The spinning wheel's principal inertias about its centre (diametral, spin, diametral)
    [kg m^2] for its ``mass`` [kg] (:data:`WHEEL_GYRATION`; diametral 0.6 of spin)."""
    i_spin = mass * WHEEL_GYRATION ** 2
    return (0.6 * i_spin, i_spin, 0.6 * i_spin)


def steer_lever(g: CornerGeometry) -> float:
    """The steering arm [m]: the tie rod's outer joint behind the kingpin axis (the line
    through the ball joints) at the joint's height, x_kingpin - x_tie_rod_outer; a rack
    travel dy turns the wheel by -dy / lever (rack left: wheel steers right) to first order."""
    lo, up, tro = g.lower_ball_joint, g.upper_ball_joint, g.tie_rod_outer
    s = (tro[2] - lo[2]) / (up[2] - lo[2])
    return float(lo[0] + s * (up[0] - lo[0]) - tro[0])



class WheelsAndDriver:
    """The wheel-side methods of the four-corner vehicle (state in the owner's ``_st``,
    ``_base``; inputs held in ``_F_road``, ``_T_wheel``, ``_rack``)."""

    client: int
    body: int
    link: list[dict[str, int]]
    r_l: np.ndarray
    steer_lever: float
    _st: dict[str, list[Any]]
    _base: tuple[Any, ...]
    _F_road: np.ndarray | None
    _T_wheel: np.ndarray
    _rack: float

    def contact_frame(self, i: int) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
        """Corner i's contact point P [m] (world) and road-plane axes (e_x forward in the
        wheel plane, e_y = n x e_x, n = world z: a flat road's normal, the point-contact
        tyre's vertical). P is the wheel centre moved the loaded radius r_l down the wheel
        plane's radial direction toward the road (the corner file's ``tyre_loaded_radius``)."""
        st = self._st
        c, a = st["wc"][i], st["axis"][i]
        n = np.array([0.0, 0.0, 1.0])
        ex = np.cross(a, n)
        ex /= np.linalg.norm(ex)
        up = np.cross(ex, a)  # radial upward in the wheel plane
        return c - self.r_l[i] * up, (ex, np.cross(n, ex), n)

    def wheel_kinematics(self) -> dict[str, np.ndarray]:
        """Per corner (arrays of 4), what the tyre needs (docs/tyres.md, "the 3-D tyre"):
        ``vx_wc``, ``vy_wc`` the wheel centre's velocity along the road-plane axes of
        :meth:`contact_frame` [m/s], ``omega_w`` the wheel's absolute spin rate about its
        axis, forward rolling positive [rad/s], ``gamma`` the inclination of the wheel plane
        to the road normal, top toward +y positive (ISO-W) [rad], ``x_wc``, ``y_wc`` the
        wheel centre's world position [m] (the contact's place on the road), ``r_l`` the
        loaded radius the slip takes as rolling radius [m]."""
        out: dict[str, list[float]] = {k: [] for k in ("vx_wc", "vy_wc", "omega_w", "gamma",
                                                       "x_wc", "y_wc")}
        for i in range(4):
            _, (ex, ey, n) = self.contact_frame(i)
            v, c, a = self._st["vwc"][i], self._st["wc"][i], self._st["axis"][i]
            out["vx_wc"].append(float(v @ ex))
            out["vy_wc"].append(float(v @ ey))
            out["omega_w"].append(self._st["spin"][i])
            out["gamma"].append(float(-np.arcsin(np.clip(a @ n, -1.0, 1.0))))
            out["x_wc"].append(float(c[0]))
            out["y_wc"].append(float(c[1]))
        d = {k: np.array(v) for k, v in out.items()}
        d["r_l"] = self.r_l.copy()
        return d

    def set_tyre_forces(self, Fx: np.ndarray, Fy: np.ndarray, Mz: np.ndarray) -> None:  # noqa: N803
        """The tyre's road-plane forces Fx, Fy [N] and aligning moment Mz [N m] per corner,
        held until changed: from now on each substep applies F_t (vertical, from
        :meth:`substep`) with them at the contact point on the wheel link."""
        self._F_road = np.column_stack([Fx, Fy, Mz]).astype(float)

    def set_driver(self, wheel_torque: np.ndarray, rack: float) -> None:
        """The driver's inputs, held until changed: the torque on each wheel's spin joint
        [N m] (drive positive, a brake negative while rolling forward; its reaction is on
        the upright) and the rack's travel [m] (+ left: the front wheels steer right,
        :func:`steer_lever`)."""
        self._T_wheel = np.asarray(wheel_torque, dtype=float).copy()
        self._rack = float(rack)

    def rack_for_steer(self, delta: float) -> float:
        """The rack travel [m] that steers the front wheels by ``delta`` [rad] (left
        positive), to first order."""
        return -delta * self.steer_lever

    def _launch(self, v: float) -> None:
        """Body and every link moving forward at ``v`` [m/s], the wheels free rolling."""
        cl, bd = self.client, self.body
        p.resetBaseVelocity(bd, [v, 0.0, 0.0], [0.0, 0.0, 0.0], physicsClientId=cl)
        for i, lk in enumerate(self.link):
            p.resetJointState(bd, lk["wheel"], 0.0, v / self.r_l[i], physicsClientId=cl)

    def body_motion(self) -> dict[str, np.ndarray]:
        """The body's planar motion (length-1 arrays): ``x``, ``y`` [m], ``yaw`` [rad],
        ``u``, ``v`` the CG's velocity along the body's heading and across it [m/s],
        ``w_yaw`` [rad/s] (world z)."""
        P, R, V, W = self._base[:4]
        yaw = float(np.arctan2(R[1, 0], R[0, 0]))
        h = np.array([np.cos(yaw), np.sin(yaw), 0.0])
        lat = np.array([-np.sin(yaw), np.cos(yaw), 0.0])
        return {"x": np.array([P[0]]), "y": np.array([P[1]]), "yaw": np.array([yaw]),
                "u": np.array([float(V @ h)]), "v": np.array([float(V @ lat)]),
                "w_yaw": np.array([float(W[2])])}
