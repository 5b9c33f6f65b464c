"""Geometry of the realistic double-wishbone corner: its hardpoints, the lower arm's frame and
named points, and its URDF (links with masses and inertias, joints). Pure numbers and text, no
PyBullet; :mod:`.double_wishbone` builds the multi-body model from them.

**Hardpoints** are data: a corner file (:mod:`cosim.corner`, docs/corners.md) read into a
:class:`CornerGeometry`; :data:`BUILTIN` is ``cosim/corners/mpv_front.toml``'s. The thesis gives
none ("the actual dimensions of the arms are not available"); ours, for a small MPV, in
metres, corner frame = vehicle axes (x forward, y left, z up) at the static wheel centre of
this **front-left** corner:

* *lower arm*: from :mod:`cosim.lower_arm`, the one definition the FE reads too (arm frame:
  bushes (+-0.13, 0, 0), ball joint (0.025, 0.294, 0), damper seat (0.064, 0.185, 0), pad
  (-0.017, 0.215, 0); origin (0, -0.354, -0.13), the corner's axes: no anti-dive, the arm
  plane horizontal at ride height). The lever 0.294 m makes the torsion bar a 31 kN/m wheel
  rate (K_theta / L^2); tests/vehicles/test_arm_geometry_consistent.py checks that the
  PyBullet corner puts the arm's points where :mod:`cosim.lower_arm` says.
* *upper arm*: bushes (+-0.14, -0.34, 0.18), ball joint (-0.005, -0.10, 0.20); 0.24 m long
  in front view, 0.82 of the lower arm (short-long: camber gain), its inner end 20 mm lower,
  so the arms meet inboard at the instant centre y = -4.06 m, z = -0.13 m: a camber gain of
  1 / 4.06 m = 1.4 deg per 100 mm of jounce at ride height (wheel top inward; the PyBullet
  corner: 0.31 deg at 20 mm, 1.06 deg at 59 mm), in the 1-2.5 deg/100 mm of passenger-car
  double wishbones; a roll centre 30 mm above the ground (the line from the contact patch,
  0.30 m below the wheel centre for a 15-16 in MPV wheel, to the instant centre, at the
  centreline); a wheel centre rising 1.015 times as fast as the ball joint (4.06 m from the
  instant centre, the ball joint 4.00 m), so a wheel-centre lever of 0.2984 m (the PyBullet
  corner: 0.2984 m) and a wheel rate K_theta / 0.2984^2 = 30.1 kN/m (Table 4.3: 31 kN/m,
  -3 %; identified: 30.0 kN/m). Parallel arms would give 0.294 m and 31.0 kN/m but no camber
  gain. The bushes are 0.28 m apart (an A-arm whose legs straddle the 50 mm damper, which
  passes between them at y = -0.19 m).
* *steering axis*: lower ball joint (0.025, -0.06, -0.13) to upper (-0.005, -0.10, 0.20):
  kingpin inclination atan(0.04 / 0.33) = 6.9 deg, caster atan(0.03 / 0.33) = 5.2 deg, the
  axis meeting the ground 39 mm inboard of the contact patch centre (positive scrub radius).
* *damper*: lower mount = the arm's seat, (0.064, -0.169, -0.13); top mount (0.064, -0.206,
  0.40), straight above it in side view: 0.53 m between mounts, leaning 4.0 deg inboard at
  the top (as front dampers lean to clear the tyre). Its motion ratio to the ball joint is
  (0.185 / 0.294) cos(4.0 deg) = 0.628; the physical 3800 N s/m acts at the wheel centre as
  3800 (0.185 cos 4 deg / 0.2984)^2 = 1454 N s/m (Table 4.3: 1500 N s/m).
* *tie rod*: outer ball joint (-0.14, -0.072, -0.03) on the steering axis, 0.14 m behind the
  axle (rear steer); inner (rack) end (-0.14, -0.350, -0.037), 0.278 m long, where the line
  from the instant centre through the outer end meets the line through the arms' inner
  pivots: no bump steer to first and second order (the PyBullet corner steers 0.002 deg at
  20 mm and 0.024 deg at 59 mm of jounce).
* *bump stop*: the jounce bumper on the body above the arm's pad; clearance, rate and the
  wheel travel to first contact (58.5 mm) in :mod:`.bump_stop`.
* *half track* 0.7055 m (t = 1.411 m, Ch. 4 extraction); the body's centre of mass is put on
  the vehicle centreline (it only moves vertically, so its position has no effect).

*Mass properties*: the built-in lower arm's are the FE arm's (:data:`cosim.lower_arm.
MASS_PROPERTIES`, scaled to its mass, its product of inertia, I_xy 6 % of I_xx, dropped: the
URDF link is axis-aligned). Another corner's lower arm is three equal point masses at its
bushes and ball joint, plus 10 % of the polar inertia on each axis for its depth (ours: a
forged A-arm's mass sits in its eyes and bosses). The hub is a wheel (spin axis y), the tie
rod a slender rod, the upper arm a small triangle.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from cosim import corner as corner_file
from cosim import lower_arm as la
from cosim.corner import Corner


class CornerMasses(Protocol):
    """The masses the URDF needs (:class:`.double_wishbone.DoubleWishboneParams`) [kg];
    read-only, so that a frozen dataclass satisfies it."""

    @property
    def body_mass(self) -> float: ...
    @property
    def hub_mass(self) -> float: ...
    @property
    def lower_arm_mass(self) -> float: ...
    @property
    def upper_arm_mass(self) -> float: ...
    @property
    def tie_rod_mass(self) -> float: ...


# link indices (joint index = child link index)
BODY, LOWER_ARM, HUB, UPPER_ARM, TIE_ROD = 0, 1, 2, 3, 4


class CornerGeometry:
    """A corner file's points as the PyBullet corner uses them (corner frame [m]), its lower
    arm's frame and named points, and its URDF."""

    def __init__(self, corner: Corner) -> None:
        self.corner = c = corner
        P = c.points
        self.wheel_centre = np.array([0.0, 0.0, 0.0])
        self.lower_bush_front = P["lower_bush_front"]
        self.lower_bush_rear = P["lower_bush_rear"]
        self.lower_ball_joint = P["lower_ball_joint"]
        self.damper_lower = P["damper_lower"]
        self.damper_upper = P["damper_upper"]
        self.bump_stop_pad = P.get("bump_stop_pad")
        self.upper_bush_front = P["upper_bush_front"]
        self.upper_bush_rear = P["upper_bush_rear"]
        self.upper_ball_joint = P["upper_ball_joint"]
        self.tie_rod_inner = P["tie_rod_inner"]
        self.tie_rod_outer = P["tie_rod_outer"]
        self.half_track = c.half_track
        o, R = la.arm_frame_of(c)
        self.arm_origin, self.arm_rotation = o, R
        hp = la.hardpoints_of(c)
        self.arm_hardpoints = hp
        """The lower arm's load points in its arm frame [m]."""
        self.fe_arm = hp.keys() == la.HARDPOINTS.keys() and all(
            np.array_equal(hp[k], la.HARDPOINTS[k]) for k in hp)
        """Whether the lower arm is the FE part (:mod:`cosim.lower_arm`: the built-in
        corner's arm points, in its arm frame; a mirrored corner's too): its mass
        properties are then the FE arm's."""
        self.arm_points = {"bush_front": self.lower_bush_front,
                           "bush_rear": self.lower_bush_rear,
                           "ball_joint": self.lower_ball_joint,
                           "damper_mount": self.damper_lower}
        if self.bump_stop_pad is not None:
            self.arm_points["bump_stop"] = self.bump_stop_pad
        self.bush_spacing = float(np.linalg.norm(self.lower_bush_front - self.lower_bush_rear))
        com_arm, self._arm_inertia_per_kg = self._arm_mass_model()
        self.lower_arm_com = self.to_corner(com_arm)
        self.arm_accel_points = {"loc1": hp["ball_joint"] - np.array([0.0, 0.020, 0.0]),
                                 "cg": com_arm, "loc2": np.array([0.0, 0.020, 0.0])}
        """Points of the lower arm whose accelerations ``plant/response`` carries (thesis
        Table 5.4), in the arm frame [m]. The thesis names them only "Loc1" (near the hub),
        "CG" and "Loc2" (near the body pivot) without a drawing, so (ours): ``loc1`` 20 mm
        inboard of the ball joint, on its boss's edge ((0.025, 0.274, 0) on the built-in
        arm); ``cg`` the arm's centre of mass (0.085 m from the pivot axis); ``loc2`` (0,
        0.020, 0), 20 mm outboard of the bush midpoint, moving almost with the body. A
        point's vertical acceleration is the body's plus the arm's angular acceleration times
        its distance from the pivot axis: it falls from Loc1 to the CG to Loc2, as in Table
        5.4."""
        self.lever_ball_joint = float(hp["ball_joint"][1])
        """Horizontal distance of the ball joint from the pivot axis, L [m]."""

    def _arm_mass_model(self) -> tuple[np.ndarray, np.ndarray]:
        """(centre of mass in the arm frame [m], diagonal inertia per kg [m^2])."""
        if self.fe_arm:
            props = la.MASS_PROPERTIES
            inertia = np.array(props["inertia_kg_m2"], dtype=float)
            return (np.array(props["centre_of_mass_m"], dtype=float),
                    np.diag(inertia) / float(props["mass_kg"]))
        hp = self.arm_hardpoints
        pts = np.array([hp["bush_front"], hp["bush_rear"], hp["ball_joint"]])
        com = pts.mean(axis=0)
        r = pts - com
        per_kg = np.array([np.mean(r[:, 1] ** 2 + r[:, 2] ** 2),
                           np.mean(r[:, 0] ** 2 + r[:, 2] ** 2),
                           np.mean(r[:, 0] ** 2 + r[:, 1] ** 2)])
        return com, per_kg + 0.1 * per_kg.sum() / 2.0

    def to_corner(self, point_arm: np.ndarray) -> np.ndarray:
        """An arm-frame point in the static corner frame [m]."""
        out: np.ndarray = self.arm_origin + self.arm_rotation @ np.asarray(point_arm, float)
        return out

    def to_arm_frame(self, point: np.ndarray) -> np.ndarray:
        """A corner-frame point in the arm frame [m]."""
        out: np.ndarray = self.arm_rotation.T @ (np.asarray(point, dtype=float)
                                                 - self.arm_origin)
        return out

    def lower_arm_inertia(self, mass: float) -> np.ndarray:
        """(I_xx, I_yy, I_zz) of the lower arm about its centre of mass [kg m^2]."""
        if self.fe_arm:  # the FE arm's tensor scaled to ``mass``
            props = la.MASS_PROPERTIES
            inertia = np.array(props["inertia_kg_m2"], dtype=float)
            out: np.ndarray = np.diag(inertia) * mass / float(props["mass_kg"])
            return out
        return self._arm_inertia_per_kg * mass

    def urdf(self, pr: CornerMasses) -> str:
        """URDF of the corner (links, inertias, joints) for the given masses. The lower arm's
        link axes are the corner's (the revolute joint's axis is the arm frame's x, given in
        them)."""
        lower, others, joints = self.arm_urdf((pr.lower_arm_mass, pr.upper_arm_mass,
                                               pr.tie_rod_mass))
        # the body's centre of mass on the vehicle centreline; hub + wheel ~ a disc about y
        s = (_link("ground", 0, [0, 0, 0], (0, 0, 0))
             + _link("body", pr.body_mass, np.array([0.0, -self.half_track, 0.25]),
                     (100, 100, 100)) + lower
             + _link("hub", pr.hub_mass, self.wheel_centre - self.lower_ball_joint,
                     (1.2, 2.0, 1.2)) + others
             + _joint("body_z", "prismatic", "ground", "body", [0, 0, 0], "0 0 1") + joints)
        return f'<?xml version="1.0"?>\n<robot name="double_wishbone">\n{s}</robot>\n'

    def arm_urdf(self, masses: tuple[float, float, float], n: str = "",
                 at: np.ndarray | None = None, rack: str = "body") -> tuple[str, str, str]:
        """The URDF of the corner's lower arm, upper arm and tie rod (masses [kg], in that
        order) with the wheel centre at ``at`` [m] (default 0): (the lower arm's link, the
        upper arm's and the tie rod's links, their joints: the arm pivots on ``body``, the
        ball joint to ``hub{n}``, the tie rod's inner joint on ``rack``), names suffixed by
        ``n``; each joint is named after its child link. The upper arm is a small triangle,
        the tie rod a slender rod along y: I_perp = m L^2 / 12, I_axis = m r^2 / 2 with
        r = 10 mm."""
        wc = np.zeros(3) if at is None else at
        m_la, m_ua, m_tr = masses
        la_o = wc + 0.5 * (self.lower_bush_front + self.lower_bush_rear)
        ua_o = wc + 0.5 * (self.upper_bush_front + self.upper_bush_rear)
        bj, tri = wc + self.lower_ball_joint, wc + self.tie_rod_inner
        ua_com = wc + (self.upper_bush_front + self.upper_bush_rear + self.upper_ball_joint) / 3.0
        tr_com = wc + 0.5 * (self.tie_rod_inner + self.tie_rod_outer)
        tr_len = float(np.linalg.norm(self.tie_rod_outer - self.tie_rod_inner))
        i_perp = m_tr * tr_len ** 2 / 12.0
        ua_axis = self.upper_bush_front - self.upper_bush_rear
        lower = _link(f"lower_arm{n}", m_la, wc + self.lower_arm_com - la_o,
                      self.lower_arm_inertia(m_la))
        others = (_link(f"upper_arm{n}", m_ua, ua_com - ua_o, (0.012, 0.01, 0.02))
                  + _link(f"tie_rod{n}", m_tr, tr_com - tri, (i_perp, m_tr * 1e-4 / 2.0, i_perp)))
        joints = (_joint(f"lower_arm{n}", "revolute", "body", f"lower_arm{n}", la_o,
                         _fmt(self.arm_rotation[:, 0]))
                  + _joint(f"hub{n}", "spherical", f"lower_arm{n}", f"hub{n}", bj - la_o)
                  + _joint(f"upper_arm{n}", "revolute", "body", f"upper_arm{n}", ua_o,
                           _fmt(ua_axis / np.linalg.norm(ua_axis)))
                  + _joint(f"tie_rod{n}", "spherical", rack, f"tie_rod{n}", tri))
        return lower, others, joints


BUILTIN = CornerGeometry(corner_file.builtin())
"""The built-in corner's geometry (``cosim/corners/mpv_front.toml``; its arm frame is
:mod:`cosim.lower_arm`'s: origin ``ARM_ORIGIN``, the corner's axes)."""


def _fmt(v) -> str:
    return " ".join(f"{float(x):.9g}" for x in v)


def _link(name, m, com, inertia):
    return (f' <link name="{name}"><inertial><origin xyz="{_fmt(com)}"/><mass value="{m}"/>'
            f'<inertia ixx="{inertia[0]:.9g}" iyy="{inertia[1]:.9g}" izz="{inertia[2]:.9g}" '
            f'ixy="0" ixz="0" iyz="0"/></inertial></link>\n')


def _joint(name, kind, parent, child, origin, axis="1 0 0"):
    return (f' <joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{_fmt(origin)}"/><axis xyz="{axis}"/>'
            f'<limit lower="-3" upper="3" effort="1e12" velocity="1e6"/></joint>\n')
