"""A driver for the four-corner vehicle: a speed profile held by wheel torques
with a brake balance, and a steering input (open loop, or a yaw-rate follower for a constant
radius). Pure numerics, no I/O, no PyBullet: it maps what the driver sees (time, the body's
forward speed u, its yaw rate r) to the plant's inputs (the torque on each wheel's spin joint
and the front wheels' steer angle).

**Speed.** The profile is a piecewise-linear v_ref(t) [m/s] (``speed``: (t, v) points, held
after the last). The longitudinal force demanded of the tyres is
F_x = m (dv_ref/dt + k_p (v_ref - u) + k_i \\int (v_ref - u) dt): the feed-forward of the
profile's slope (an 0.8 g stop brakes at 0.8 g from the first instant) and a PI on the speed
error (k_p = 2 1/s, k_i = 0.5 1/s^2, ours: a human driver's bandwidth of ~0.3 Hz, slow
beside the pitch mode). It becomes wheel torques T_i = F_x,i r_l: braking (F_x < 0) shared
``brake_balance`` to the front axle (default 0.72: the ideal balance of the built-in vehicle
at 0.8 g, its front share of the tyre loads then: (W_f + m a h / L) / m g = 0.72), driving
to the ``driven`` axle. Left = right. Below ``v_stop`` the brakes are released (the MF tyre
and a stopped wheel need MF-Tyre's low-speed treatment: :mod:`nodes.tyre_road.tyre_3d`).

**Steering.** Open loop: ``steer`` (t, delta) points [rad], piecewise linear, left
positive. Or a constant ``radius`` R [m] (left turn positive): the yaw rate wanted is
r_ref = u / R, the steer the Ackermann angle L / R plus a PI on the yaw-rate error
(k_p = 0.1 s, k_i = 0.5, ours: the understeer gradient is what the integral finds).
Either way the steer moves at most ``steer_rate`` (0.5 rad/s at the wheels, ~8 rad/s at a
16:1 hand wheel, ours: a brisk driver; an unlimited step put 1.6 MN on the ball joints).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np


def _interp(points: Sequence[Sequence[float]], t: float) -> tuple[float, float]:
    """(value, slope) of the piecewise-linear (t, value) ``points`` at ``t`` (held outside)."""
    ts = np.array([q[0] for q in points], dtype=float)
    vs = np.array([q[1] for q in points], dtype=float)
    if t <= ts[0] or t >= ts[-1] or len(ts) == 1:
        return float(np.interp(t, ts, vs)), 0.0
    j = int(np.searchsorted(ts, t, side="right")) - 1
    slope = (vs[j + 1] - vs[j]) / (ts[j + 1] - ts[j])
    return float(vs[j] + slope * (t - ts[j])), float(slope)


@dataclass
class Driver:
    """The driver (module docstring). Units SI; torques on the wheels FL, FR, RL, RR."""

    mass: float
    """m [kg]: the whole vehicle's (body and unsprung)."""
    wheel_radius: float
    """r_l [m]: the torque arm of the tyre's F_x."""
    wheelbase: float
    speed: Sequence[Sequence[float]]
    steer: Sequence[Sequence[float]] = ((0.0, 0.0),)
    radius: float | None = None
    brake_balance: float = 0.72
    driven: str = "front"
    kp: float = 2.0
    ki: float = 0.5
    kp_yaw: float = 0.1
    ki_yaw: float = 0.5
    v_stop: float = 1.0
    steer_rate: float = 0.5
    _delta: float = field(default=0.0, init=False)
    _int_v: float = field(default=0.0, init=False)
    _int_r: float = field(default=0.0, init=False)

    def __post_init__(self) -> None:
        if not 0.0 <= self.brake_balance <= 1.0:
            raise ValueError(f"brake_balance = {self.brake_balance}: expected 0..1")
        if self.driven not in ("front", "rear", "all"):
            raise ValueError(f"driven = {self.driven!r}: expected 'front', 'rear' or 'all'")
        for name, pts in (("speed", self.speed), ("steer", self.steer)):
            ts = [q[0] for q in pts]
            if not pts or any(len(q) != 2 for q in pts) or ts != sorted(ts):
                raise ValueError(f"{name}: expected (t, value) points in time order")
        if self.radius is not None and self.radius == 0.0:
            raise ValueError("radius = 0: expected a radius [m], + left, - right")

    def longitudinal_force(self, t: float, u: float, dt: float) -> float:
        """F_x [N] demanded of the four tyres together at time ``t`` [s], forward speed
        ``u`` [m/s]; ``dt`` [s] since the last call (the integral's)."""
        v_ref, a_ref = _interp(self.speed, t)
        err = v_ref - u
        self._int_v += err * dt
        return self.mass * (a_ref + self.kp * err + self.ki * self._int_v)

    def wheel_torques(self, F_x: float, u: float) -> np.ndarray:  # noqa: N803
        """T_i [N m] on FL, FR, RL, RR for the total ``F_x`` (module docstring)."""
        if F_x < 0.0:
            if u < self.v_stop:
                return np.zeros(4)
            b = self.brake_balance
            share = np.array([b, b, 1.0 - b, 1.0 - b]) / 2.0
        else:
            share = {"front": np.array([0.5, 0.5, 0.0, 0.0]),
                     "rear": np.array([0.0, 0.0, 0.5, 0.5]),
                     "all": np.full(4, 0.25)}[self.driven]
        return F_x * share * self.wheel_radius

    def steer_angle(self, t: float, u: float, r: float, dt: float) -> float:
        """delta [rad] of the front wheels (left positive) at ``t``, speed ``u``, yaw rate
        ``r`` [rad/s]."""
        if self.radius is None:
            want = _interp(self.steer, t)[0]
        else:
            err = u / self.radius - r
            self._int_r += err * dt
            want = self.wheelbase / self.radius + self.kp_yaw * err + self.ki_yaw * self._int_r
        step = self.steer_rate * dt
        self._delta += float(np.clip(want - self._delta, -step, step))
        return self._delta

    def command(self, t: float, u: float, r: float, dt: float) -> tuple[np.ndarray, float]:
        """(wheel torques [N m], steer angle [rad]) at ``t`` (module docstring)."""
        return (self.wheel_torques(self.longitudinal_force(t, u, dt), u),
                self.steer_angle(t, u, r, dt))
