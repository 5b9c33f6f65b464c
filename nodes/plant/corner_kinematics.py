"""Kinematics and compliance of a double-wishbone corner file, solved as a linkage: pure
numerics (no PyBullet, no I/O), what ``suscosim corner check`` prints.

The body is held; the lower arm turns by theta [rad] about its pivot axis (the line through
its two bushes; positive: the outer end up, jounce, on the left corner). For each theta:

1. the lower ball joint turns with the arm;
2. the upper arm turns by phi about its own pivot axis until its ball joint is at the
   upright's fixed distance from the lower one (one equation in phi, Newton from the last
   solution);
3. the upright is the rigid body through the two ball joints: the rotation that carries the
   static kingpin line onto the new one (the smallest rotation), then a turn psi about that
   line until the tie rod's outer joint is at the tie rod's length from its inner joint (one
   equation in psi); the wheel centre and the spin axis (static: along y, no static camber
   or toe) move with it.

From the pose: wheel travel z_w [m], camber gamma [rad] (ISO, top outward positive: gamma =
asin(-a_z) for the left wheel's spin axis a), toe delta [rad] (toe-in positive, atan2(a_x,
a_y)), the damper's length and compression, the pad's rise. Rates by central differences in
theta (1e-5 rad, error ~1e-10 relative), chained to travel: MR_d = -dL_d/dz_w, and the wheel
rate from virtual work (U(theta) of the springs and bumper, F = dU/dz_w, k = dF/dz_w):

    F(z) = (tau_0 + K_theta theta) / z' + k_c (L_s0 - L_s + s_0) (-L_s') / z' + F_bs pad' / z'

with z' = dz_w/dtheta and the static preload tau_0 (torsion bar) or s_0 (coil: it carries the
static load when fitted) chosen so that F(0) = M_b g (the arms' share of their 15 kg left
out: 0.3 % of the load). The elastic part at ride height is K_theta / z'^2 + k_c MR_s^2; the
rest is the preload acting through the change of the lever.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cosim.corner import Corner

from .bump_stop import BumpStopParams, bump_stop_force
from .model import GRAVITY

_H = 1e-5
"""Central-difference step in theta [rad]."""


def _rot(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix of ``angle`` [rad] about the unit vector ``axis`` (Rodrigues)."""
    x, y, z = axis
    c, s = math.cos(angle), math.sin(angle)
    C = 1.0 - c
    return np.array([[c + x * x * C, x * y * C - z * s, x * z * C + y * s],
                     [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
                     [z * x * C - y * s, z * y * C + x * s, c + z * z * C]])


def _align(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation carrying the direction of ``a`` onto that of ``b``."""
    a = a / np.linalg.norm(a)
    b = b / np.linalg.norm(b)
    v = np.cross(a, b)
    s = float(np.linalg.norm(v))
    if s < 1e-15:
        return np.eye(3)
    return _rot(v / s, math.atan2(s, float(a @ b)))


def _newton(f, x0: float, what: str) -> float:
    """Root of a smooth scalar function near ``x0`` (secant-free Newton, numeric slope)."""
    x = x0
    for _ in range(50):
        fx = f(x)
        if abs(fx) < 1e-13:
            return x
        d = (f(x + 1e-7) - f(x - 1e-7)) / 2e-7
        if d == 0.0 or not math.isfinite(d):
            break
        x -= fx / d
    if abs(f(x)) < 1e-10:
        return x
    raise ValueError(f"the linkage does not close ({what}): the arms cannot reach")


@dataclass(frozen=True)
class Pose:
    """The corner at one lower-arm angle (corner frame, body held) [m, rad]."""

    theta: float
    phi: float
    psi: float
    wheel_centre: np.ndarray
    spin_axis: np.ndarray
    damper_length: float
    pad: np.ndarray | None
    spring_length: float | None

    @property
    def camber(self) -> float:
        """gamma [rad], ISO: positive top outward (left wheel)."""
        return math.asin(-float(self.spin_axis[2]))

    @property
    def toe(self) -> float:
        """delta [rad], toe-in positive (left wheel)."""
        return math.atan2(float(self.spin_axis[0]), float(self.spin_axis[1]))


class CornerLinkage:
    """The kinematic chain of a corner file (module docstring)."""

    def __init__(self, corner: Corner) -> None:
        self.corner = c = corner
        P = c.points
        self.lf, self.lr = P["lower_bush_front"], P["lower_bush_rear"]
        self.uf, self.ur = P["upper_bush_front"], P["upper_bush_rear"]
        self.lbj0, self.ubj0 = P["lower_ball_joint"], P["upper_ball_joint"]
        self.tri, self.tro0 = P["tie_rod_inner"], P["tie_rod_outer"]
        self.d_lo, self.d_up = P["damper_lower"], P["damper_upper"]
        self.pad0 = P.get("bump_stop_pad")
        self.s_lo, self.s_up = P.get("spring_lower"), P.get("spring_upper")
        self.ax_l = (self.lf - self.lr) / np.linalg.norm(self.lf - self.lr)
        self.ax_u = (self.uf - self.ur) / np.linalg.norm(self.uf - self.ur)
        if np.cross(self.ax_l, self.lbj0 - self.lr) @ np.array([0.0, 0.0, 1.0]) < 0:
            self.ax_l = -self.ax_l  # positive theta: the ball joint up (jounce)
        if np.cross(self.ax_u, self.ubj0 - self.ur) @ np.array([0.0, 0.0, 1.0]) < 0:
            self.ax_u = -self.ax_u
        self.kingpin0 = self.ubj0 - self.lbj0
        self.L_ball = float(np.linalg.norm(self.kingpin0))
        self.L_tie = float(np.linalg.norm(self.tro0 - self.tri))
        self._last = (0.0, 0.0)

    def _lower(self, theta: float, p: np.ndarray) -> np.ndarray:
        return self.lr + _rot(self.ax_l, theta) @ (p - self.lr)

    def pose(self, theta: float) -> Pose:
        """The corner with the lower arm turned by ``theta`` [rad] (ValueError if the
        linkage does not close there)."""
        lbj = self._lower(theta, self.lbj0)

        def upper(phi: float) -> np.ndarray:
            return self.ur + _rot(self.ax_u, phi) @ (self.ubj0 - self.ur)

        phi = _newton(lambda f: float(np.linalg.norm(upper(f) - lbj)) - self.L_ball,
                      self._last[0], "upper arm")
        ubj = upper(phi)
        k = ubj - lbj
        Q = _align(self.kingpin0, k)
        kn = k / np.linalg.norm(k)

        def upright(psi: float) -> np.ndarray:
            return _rot(kn, psi) @ Q

        psi = _newton(lambda s: float(np.linalg.norm(lbj + upright(s) @ (self.tro0 - self.lbj0)
                                                     - self.tri)) - self.L_tie,
                      self._last[1], "tie rod")
        self._last = (phi, psi)
        Ru = upright(psi)
        wc = lbj + Ru @ (np.zeros(3) - self.lbj0)
        top = self.d_up
        L_d = float(np.linalg.norm(top - self._lower(theta, self.d_lo)))
        pad = None if self.pad0 is None else self._lower(theta, self.pad0)
        L_s = None
        if self.s_lo is not None and self.s_up is not None:
            L_s = float(np.linalg.norm(self.s_up - self._lower(theta, self.s_lo)))
        return Pose(theta, phi, psi, wc, Ru @ np.array([0.0, 1.0, 0.0]), L_d, pad, L_s)

    def theta_at_travel(self, z: float) -> float:
        """The lower-arm angle [rad] at wheel travel ``z`` [m] (wheel centre's rise)."""
        self._last = (0.0, 0.0)
        return _newton(lambda t: float(self.pose(t).wheel_centre[2]) - z, 0.0, "travel")


def _d(f, x: float, h: float = _H) -> tuple[float, float, float]:
    """(f, f', f'') at x by central differences."""
    fm, f0, fp = f(x - h), f(x), f(x + h)
    return f0, (fp - fm) / (2 * h), (fp - 2 * f0 + fm) / (h * h)


def curves(corner: Corner, travel: np.ndarray) -> dict[str, np.ndarray]:
    """The kinematic and compliance curves at the wheel travels ``travel`` [m]:
    ``z_w`` [m], ``theta`` [rad], ``camber``, ``toe`` [rad], ``mr_damper`` [-],
    ``wheel_rate`` [N/m] (springs and bumper, preload included), ``wheel_rate_elastic``
    [N/m] (K_theta / z'^2 + k_c MR_s^2, no preload term), ``wheel_load`` [N] (dU/dz_w: what
    holds the wheel at that travel), ``bump_stop_force`` [N] (at the pad)."""
    lk = CornerLinkage(corner)
    c = corner
    k_theta = c.torsion_bar_nm_per_deg * 180.0 / math.pi
    k_c = c.coil_n_per_m
    bs = None if c.bump_stop is None else BumpStopParams(**c.bump_stop)
    W = c.masses["body"] * GRAVITY  # the sprung weight the springs carry at ride height

    def z(t: float) -> float:
        return float(lk.pose(t).wheel_centre[2])

    def L_s(t: float) -> float:
        return float(lk.pose(t).spring_length or 0.0)

    # static preload: F(0) = W through the spring that carries the load
    _, z1_0, _ = _d(z, 0.0)
    if k_c > 0:
        _, Ls1_0, _ = _d(L_s, 0.0)
        tau0, s0 = 0.0, W * z1_0 / -Ls1_0  # coil's static force [N], compression
    else:
        tau0, s0 = W * z1_0, 0.0
    L_s0 = L_s(0.0) if k_c > 0 else 0.0
    pad_z0 = None if lk.pad0 is None else float(lk.pad0[2])

    def energy_rate(t: float) -> float:
        """dU/dtheta [N m]: the generalised force the springs and bumper put on theta."""
        q = tau0 + k_theta * t
        if k_c > 0:
            _, Ls1, _ = _d(L_s, t)
            q += (s0 + k_c * (L_s0 - L_s(t))) * -Ls1
        if bs is not None and pad_z0 is not None:
            def pad(tt: float) -> float:
                return float(lk.pose(tt).pad[2])  # type: ignore[index]
            p0, p1, _ = _d(pad, t)
            q += bump_stop_force(p0 - pad_z0 - bs.clearance, bs) * p1
        return q

    out = {k: np.empty(len(travel)) for k in
           ("z_w", "theta", "camber", "toe", "mr_damper", "wheel_rate",
            "wheel_rate_elastic", "wheel_load", "bump_stop_force")}
    for i, zw in enumerate(travel):
        t = lk.theta_at_travel(float(zw))
        ps = lk.pose(t)
        _, z1, _ = _d(z, t)
        _, Ld1, _ = _d(lambda tt: lk.pose(tt).damper_length, t)
        Q0, Q1, _ = _d(energy_rate, t, 1e-4)
        _, _, z2 = _d(z, t)
        F = Q0 / z1
        k = (Q1 - F * z2) / z1 ** 2  # d(Q/z')/dz = (Q' z' - Q z'') / z'^3
        el = k_theta / z1 ** 2
        if k_c > 0:
            _, Ls1, _ = _d(L_s, t)
            el += k_c * (Ls1 / z1) ** 2
        f_bs = 0.0
        if bs is not None and ps.pad is not None and pad_z0 is not None:
            f_bs = bump_stop_force(float(ps.pad[2]) - pad_z0 - bs.clearance, bs)
        vals = {"z_w": float(ps.wheel_centre[2]), "theta": t, "camber": ps.camber,
                "toe": ps.toe, "mr_damper": -Ld1 / z1, "wheel_rate": k,
                "wheel_rate_elastic": el, "wheel_load": F, "bump_stop_force": f_bs}
        for key, v in vals.items():
            out[key][i] = v
    return out


def equivalent_quarter_car(corner: Corner) -> dict[str, float]:
    """The lumped 2-DOF quarter car the corner acts as at ride height: m_s = M_b,
    m_u = hub + arms + tie rod [kg] (Table 4.3's convention), k_s = the wheel rate at
    z_w = 0 [N/m], c_s = c_nominal MR_d^2 [N s/m] (the damper seen at the wheel centre),
    f_body = sqrt(k_s k_t / (k_s + k_t) / m_s) / 2 pi is left to the caller (no tyre here)."""
    cv = curves(corner, np.array([0.0]))
    m = corner.masses
    mr = float(cv["mr_damper"][0])
    return {"m_s": m["body"], "m_u": m["hub"] + m["lower_arm"] + m["upper_arm"] + m["tie_rod"],
            "k_s": float(cv["wheel_rate"][0]), "k_s_elastic": float(cv["wheel_rate_elastic"][0]),
            "c_s": corner.damper_c_nominal * mr ** 2, "mr_damper": mr}


def lateral_compliance(corner: Corner) -> dict[str, float] | None:
    """Front-view compliance under a lateral force F_y at the contact patch (ride height),
    from the arms' body bushes (radial rate; the joints and links rigid): the two ball
    joints take F_y in the ratio of their heights over the contact patch (moments about the
    other joint), each arm's share goes to its bushes in the ratio of the ball joint's fore-
    aft position between them, the bushes deflect by F / k_radial and each ball joint moves
    by its arm's interpolated bush deflection. Returns the wheel centre's lateral stiffness
    [N/m] and the camber compliance [rad/N] (positive: top outward under an outward force),
    or None when the file gives no bushes."""
    b = corner.bushes
    if not all(n in b for n in ("lower_front", "lower_rear", "upper_front", "upper_rear")):
        return None
    P = corner.points
    z_cp = -corner.tyre_loaded_radius
    zl, zu = float(P["lower_ball_joint"][2]), float(P["upper_ball_joint"][2])
    # moments about the lower ball joint: F_u (zu - zl) = F (z_cp - zl), F = 1 N outward
    F_u = (z_cp - zl) / (zu - zl)
    F_l = 1.0 - F_u

    def shift(arm: str, F: float) -> float:
        f, r, bj = P[f"{arm}_bush_front"], P[f"{arm}_bush_rear"], P[f"{arm}_ball_joint"]
        w = float((bj[0] - r[0]) / (f[0] - r[0]))  # share of the front bush
        d_f = F * w / b[f"{arm}_front"].radial
        d_r = F * (1.0 - w) / b[f"{arm}_rear"].radial
        return w * d_f + (1.0 - w) * d_r

    y_l, y_u = shift("lower", F_l), shift("upper", F_u)
    gamma = (y_u - y_l) / (zu - zl)  # rad per N: the upright's roll in front view
    y_wc = y_l + gamma * (0.0 - zl)
    return {"lateral_stiffness_wc": 1.0 / y_wc, "camber_compliance": gamma,
            "ball_joint_share_upper": F_u}
