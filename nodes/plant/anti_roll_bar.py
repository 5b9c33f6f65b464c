"""Anti-roll bars of the four-corner double-wishbone vehicle: one per axle, a torsion
bar across the body whose ends turn with the two lower arms of the axle.

**Data.** Each bar is its roll stiffness at the wheels, K_bar [N m/rad of body roll, wheels
on the ground, tyres rigid] (``FullVehicleDWParams.arb_front_nm_per_deg``,
``arb_rear_nm_per_deg``, in N m/deg as usually quoted): a bar of torsional stiffness k_bar
[N m/rad], arms a [m], drop links at motion ratio MR gives K_bar = k_bar (MR / a)^2 t^2, the
number a bar is designed for (its dimensions need not be given).

**Model.** The bar couples the axle's two lower arms by their jounce angles
alpha_i = side_i (theta_i - theta_i,0) (the arm angle from static, jounce positive: the
``arm_angle`` of the state): a torque on each arm about its pivot axis

    tau_L = -K_a (alpha_L - alpha_R),   tau_R = -K_a (alpha_R - alpha_L),

reacted on the body (as the torsion bar's joint torque). A body roll phi moves the arms by
-+ t phi / (2 l) (l = dz_wc / dtheta at ride height, :func:`wheel_lever`: 0.2984 m for the
built-in corner), so the roll moment is K_a t^2 phi / l^2: K_a = K_bar l^2 / t^2. Heave and
pitch leave it unloaded.

**The arm loads.** The bar's torque enters each lower arm at its pivot, in the arm channel's
``torsion_bar_mx`` with the torsion bar's (drop links would load the link's eye instead: a
point force, not modelled).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cosim.corner import Corner

from .corner_kinematics import CornerLinkage


def wheel_lever(corner: Corner, h: float = 1e-5) -> float:
    """l = dz_wc / dtheta [m] at ride height: how far the wheel centre rises per radian of
    the lower arm (central difference of the corner file's linkage, ``h`` [rad])."""
    lk = CornerLinkage(corner)
    return float((lk.pose(h).wheel_centre[2] - lk.pose(-h).wheel_centre[2]) / (2.0 * h))


@dataclass(frozen=True)
class AntiRollBar:
    """One axle's bar: ``roll_stiffness`` K_bar [N m/rad] at the wheels, the axle's
    ``track`` t [m] and the corners' wheel-centre ``lever`` l [m] (module docstring)."""

    roll_stiffness: float
    track: float
    lever: float

    def __post_init__(self) -> None:
        for name in ("roll_stiffness", "track", "lever"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0.0) or (name != "roll_stiffness" and v == 0.0):
                raise ValueError(f"anti-roll bar {name} = {v!r}: expected a number > 0")

    @property
    def arm_stiffness(self) -> float:
        """K_a [N m/rad]: the torque on each arm per radian of arm-angle difference."""
        return self.roll_stiffness * self.lever ** 2 / self.track ** 2

    def torques(self, alpha_left: float, alpha_right: float) -> tuple[float, float]:
        """The torques [N m] on the left and right arms, jounce-positive, for their jounce
        angles [rad]."""
        m = -self.arm_stiffness * (alpha_left - alpha_right)
        return m, -m


def axle_torques(bars: tuple[AntiRollBar | None, AntiRollBar | None], alpha: np.ndarray
                 ) -> np.ndarray:
    """The bars' jounce-positive torques on the four arms FL, FR, RL, RR [N m] for their
    jounce angles ``alpha`` [rad]; an axle without a bar (None) gets none."""
    out = np.zeros(4)
    for k, bar in enumerate(bars):
        if bar is not None:
            out[2 * k], out[2 * k + 1] = bar.torques(float(alpha[2 * k]),
                                                     float(alpha[2 * k + 1]))
    return out


ARB_FRONT_NM_PER_DEG = 1200.0
"""The built-in vehicle's front bar, roll stiffness at the wheels [N m/deg] (ours: the thesis
gives no bar). Chosen with :data:`ARB_REAR_NM_PER_DEG` for (a) a roll gradient of ~5 deg/g, in
the ~4-6 deg/g usually quoted for passenger cars (the textbook range, e.g. Gillespie,
Fundamentals of Vehicle Dynamics, Ch 8; the page not re-checked here), and (b) a front share
of the roll stiffness above the front's 57 % share of the weight, as a front-heavy car is set
up to understeer.
With the built-in corner's 29.45 kN/m wheel rate (K_spring = k_w t^2 / 2 = 512 N m/deg per
axle) the suspension's roll stiffness is 1712 + 1012 = 2724 N m/deg, 63 % at the front; with
the 239 kN/m tyres in series (k_t t^2 / 2 = 4152 N m/deg per axle) the axles' are 1212 + 814
N m/deg = 116.1 kN m/rad, 60 % front; m_s g (h_cg - h_rc) = 1870 x 9.81 x 0.52 = 9.54 kN m
gives the roll gradient 9.54 / (116.1 - 9.54) = 0.0896 rad/g = 5.1 deg/g (docs/corners.md,
"Anti-roll bars", has the hand calculation the test checks)."""
ARB_REAR_NM_PER_DEG = 500.0
"""The rear bar [N m/deg] (:data:`ARB_FRONT_NM_PER_DEG`)."""


def axle_bars(front: Corner, rear: Corner, on: bool, front_nm_per_deg: float,
              rear_nm_per_deg: float) -> tuple[AntiRollBar | None, AntiRollBar | None]:
    """The front and rear bars of a vehicle on the ``front`` and ``rear`` (left) corner
    files, their roll stiffnesses at the wheels in N m/deg; (None, None) if not ``on``."""
    if not on:
        return None, None
    return tuple(AntiRollBar(k * 180.0 / math.pi, 2.0 * c.half_track, wheel_lever(c))  # type: ignore[return-value]
                 for c, k in ((front, front_nm_per_deg), (rear, rear_nm_per_deg)))
