"""Geometry of the realistic double-wishbone corner: its hardpoints, the lower arm's frame and
named points, and its URDF (links with masses and inertias, joints). Pure numbers and text, no
PyBullet; :mod:`.double_wishbone` builds the multi-body model from them.

**Hardpoints** (the thesis gives none: "the actual dimensions of the arms are not available";
plausible values for a small MPV, our reasoning). Corner frame = vehicle axes (x forward,
y left, z up) with origin at the static wheel centre of this **front-left** corner (outboard
= +y, so the arm frame has z up). Metres.

* *lower arm*: every point comes from :mod:`cosim.lower_arm`, the one definition the fatigue
  worker's FE reads too (bushes (+-0.13, 0, 0), ball joint (0.025, 0.294, 0), damper seat
  (0.064, 0.185, 0) on the front leg, bump-stop pad (-0.017, 0.215, 0) on the rear leg, in
  the arm frame; frame origin
  ``ARM_ORIGIN`` = (0, -0.354, -0.13) in the corner frame, axes parallel to the corner's: the
  pivot axis along x, so no anti-dive, and the arm plane horizontal at static ride height).
  The lever 0.294 m is what makes the torsion bar a 31 kN/m wheel rate (K_theta / L^2);
  ``tests/vehicles/test_arm_geometry_consistent.py`` checks that the PyBullet corner puts the
  arm's points where :mod:`cosim.lower_arm` says.
* *upper arm*: bushes (+-0.14, -0.34, 0.18), ball joint (-0.005, -0.10, 0.20); 0.24 m long
  in front view, 0.82 of the lower arm (a short-long arm: the shorter upper arm gives camber
  gain). Its inner end is 20 mm lower than its outer end, so the two arms converge inboard:
  in front view the upright's instant centre is where the lines of the arms meet,
  y = -4.06 m, z = -0.13 m (front-view swing arm 4.06 m), which gives
  - camber gain 1 / 4.06 m = 1.4 deg per 100 mm of jounce at ride height (wheel top inward;
    the PyBullet corner: 0.31 deg at 20 mm, 1.06 deg at 59 mm), in the 1-2.5 deg/100 mm of
    passenger-car double wishbones;
  - a roll centre 30 mm above the ground (the line from the contact patch, 0.30 m below the
    wheel centre for a 15-16 in MPV wheel, to the instant centre, at the centreline);
  - a wheel centre that rises 1.015 times as fast as the ball joint (it is 4.06 m from the
    instant centre, the ball joint 4.00 m), so the wheel-centre lever is 0.2984 m (the
    PyBullet corner: 0.2984 m) and the wheel rate K_theta / 0.2984^2 = 30.1 kN/m (Table 4.3:
    31 kN/m, -3 %; identified: 30.0 kN/m). Parallel arms would give 0.294 m and 31.0 kN/m,
    but no camber gain. A shorter upper arm (0.20 m, swing arm 3.4 m) was tried first: 29.9
    kN/m kinematically but 29.1 kN/m identified (its lever changes faster with the arm angle,
    and the 1.6 kN m preload acting through that change softens the rate).
  The bushes are 0.28 m apart (an A-arm whose legs straddle the damper, 50 mm in diameter,
  which passes between them at y = -0.19 m).
* *steering axis*: lower ball joint (0.025, -0.06, -0.13) to upper (-0.005, -0.10, 0.20):
  kingpin inclination atan(0.04 / 0.33) = 6.9 deg, caster atan(0.03 / 0.33) = 5.2 deg, the
  axis meeting the ground 39 mm inboard of the contact patch centre (positive scrub radius).
* *damper*: lower mount = the arm's seat, (0.064, -0.169, -0.13); top mount (0.064, -0.206,
  0.40), straight above it in side view: 0.53 m between mounts, leaning 4.0 deg inboard at
  the top (as front dampers lean to clear the tyre). Its motion ratio to the ball joint is
  (0.185 / 0.294) cos(4.0 deg) = 0.628,
  and the physical 3800 N s/m acts at the wheel centre as 3800 (0.185 cos 4 deg / 0.2984)^2
  = 1454 N s/m (Table 4.3: 1500 N s/m).
* *tie rod*: outer ball joint (-0.14, -0.072, -0.03) on the steering axis, 0.14 m behind the
  axle (rear steer); inner (rack) end (-0.14, -0.350, -0.037), 0.278 m long. The inner end is
  where the line from the upright's instant centre through the outer end meets the line
  through the two arms' inner pivots: the tie rod then points at the instant centre, so its
  length does not change to first order as the upright moves (no bump steer to first order),
  and the arc it swings matches the upright's (the second-order condition). The PyBullet
  corner steers 0.002 deg at 20 mm and 0.024 deg at 59 mm of jounce.
* *bump stop*: the jounce bumper on the body above the arm's pad; clearance, rate and the
  wheel travel to first contact (58.5 mm) in :mod:`.bump_stop`.
* *half track* 0.7055 m (t = 1.411 m, Ch. 4 extraction); the body's centre of mass is put on
  the vehicle centreline (it only moves vertically, so its position has no effect).

*Mass properties*: the lower arm's centre of mass is the centroid of its three joints; its
inertia is that of half its mass spread as a uniform triangle and half lumped in the three
bosses, over a 40 mm section depth (:func:`lower_arm_inertia`: I_xx 0.061, I_yy 0.048,
I_zz 0.107 kg m^2 about the centre of mass; the product I_xy = -0.005 kg m^2 is neglected).
The hub's inertia is a wheel's (spin axis y), the tie rod is a slender rod, the upper arm a
small triangle.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from cosim import lower_arm as la


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


# ---- hardpoints in the corner frame [m] (see module docstring) ----
WHEEL_CENTRE = np.array([0.0, 0.0, 0.0])
ARM_ORIGIN = la.ARM_ORIGIN
"""Lower-arm frame origin (bush midpoint) in the corner frame; arm axes = corner axes."""
# lower arm: cosim.lower_arm, arm frame -> corner frame
LOWER_BUSH_FRONT = la.to_corner(la.BUSH_FRONT)
LOWER_BUSH_REAR = la.to_corner(la.BUSH_REAR)
LOWER_BALL_JOINT = la.to_corner(la.BALL_JOINT)
DAMPER_LOWER = la.to_corner(la.DAMPER_MOUNT)
BUMP_STOP_PAD = la.to_corner(la.BUMP_STOP_PAD)
DAMPER_UPPER = np.array([DAMPER_LOWER[0], -0.206, 0.40])  # above the seat: no fore-aft lean
UPPER_BUSH_FRONT = np.array([0.14, -0.34, 0.18])
UPPER_BUSH_REAR = np.array([-0.14, -0.34, 0.18])
UPPER_BALL_JOINT = np.array([-0.005, -0.10, 0.20])
TIE_ROD_INNER = np.array([-0.14, -0.350, -0.037])
TIE_ROD_OUTER = np.array([-0.14, -0.072, -0.03])
HALF_TRACK = 0.7055

LOWER_ARM_COM = la.to_corner(np.array(la.MASS_PROPERTIES["centre_of_mass_m"]))
"""Lower arm's centre of mass (corner frame) [m]: the FE arm's (cosim.lower_arm)."""


def arm_frame() -> tuple[np.ndarray, np.ndarray]:
    """(origin, R): the lower-arm frame in the corner frame at static ride height; columns of
    R are the arm's x, y, z axes, so p_arm = R.T @ (p_corner - origin)."""
    o = 0.5 * (LOWER_BUSH_FRONT + LOWER_BUSH_REAR)
    ex = LOWER_BUSH_FRONT - LOWER_BUSH_REAR
    ex /= np.linalg.norm(ex)
    d = LOWER_BALL_JOINT - o
    ey = d - ex * (d @ ex)
    ey /= np.linalg.norm(ey)
    return o, np.column_stack([ex, ey, np.cross(ex, ey)])


def to_arm_frame(point: np.ndarray) -> np.ndarray:
    """A corner-frame point in the arm frame [m]."""
    o, R = arm_frame()
    return R.T @ (np.asarray(point, dtype=float) - o)


ARM_POINTS = {
    "bush_front": LOWER_BUSH_FRONT, "bush_rear": LOWER_BUSH_REAR,
    "ball_joint": LOWER_BALL_JOINT, "damper_mount": DAMPER_LOWER,
    "bump_stop": BUMP_STOP_PAD,
}
"""The lower arm's load points (corner frame); :func:`to_arm_frame` gives them in the arm frame
(equal to :data:`cosim.lower_arm.HARDPOINTS`, tested)."""

ARM_ACCEL_POINTS = {
    "loc1": la.BALL_JOINT - np.array([0.0, 0.020, 0.0]),
    "cg": np.array(la.MASS_PROPERTIES["centre_of_mass_m"], dtype=float),
    "loc2": np.array([0.0, 0.020, 0.0]),
}
"""Points of the lower arm whose accelerations ``plant/response`` carries (thesis Table 5.4),
in the arm frame [m]. The thesis names them only "Loc1" (near the hub), the arm's "CG" and
"Loc2" (near the body pivot / gearbox); its arm drawing is not available, so:

* ``loc1``: 20 mm inboard of the ball joint along the arm's y (toward the pivot axis),
  (0.025, 0.274, 0): on the ball-joint boss's edge, the nearest arm material to the hub that
  is not the joint itself, 0.274 m from the pivot axis;
* ``cg``: the arm's centre of mass (:data:`cosim.lower_arm.MASS_PROPERTIES`), 0.085 m from
  the pivot axis;
* ``loc2``: 20 mm outboard of the bush midpoint (the arm-frame origin), (0, 0.020, 0): on the
  base member between the bush eyes, 0.020 m from the pivot axis, so it moves almost with
  the body.

For an arm turning about its pivot axis (x) the vertical acceleration of a point is the
body's plus the arm's angular acceleration times the point's distance from that axis, so
it falls from Loc1 to the CG to Loc2, as in Table 5.4."""

ARM_ROTATION = arm_frame()[1]
"""The arm frame's axes in the corner frame at static ride height (columns x, y, z)."""
BUSH_SPACING = float(np.linalg.norm(LOWER_BUSH_FRONT - LOWER_BUSH_REAR))
"""Distance between the two lower bush centres, d [m]."""


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


def lower_arm_inertia(mass: float) -> np.ndarray:
    """(I_xx, I_yy, I_zz) of the lower arm about its centre of mass [kg m^2]: the FE arm's
    inertia tensor (:data:`cosim.lower_arm.MASS_PROPERTIES`) scaled to ``mass``; its one
    product of inertia (I_xy, 6 % of I_xx) is dropped (the URDF link is axis-aligned)."""
    props = la.MASS_PROPERTIES
    inertia = np.array(props["inertia_kg_m2"], dtype=float)
    return np.diag(inertia) * mass / float(props["mass_kg"])


# link indices (joint index = child link index)
BODY, LOWER_ARM, HUB, UPPER_ARM, TIE_ROD = 0, 1, 2, 3, 4


def corner_urdf(pr: CornerMasses) -> str:
    """URDF of the corner (links, inertias, joints) for the given masses."""
    la_o = 0.5 * (LOWER_BUSH_FRONT + LOWER_BUSH_REAR)
    ua_o = 0.5 * (UPPER_BUSH_FRONT + UPPER_BUSH_REAR)
    ua_com = (UPPER_BUSH_FRONT + UPPER_BUSH_REAR + UPPER_BALL_JOINT) / 3.0
    tr_com = 0.5 * (TIE_ROD_INNER + TIE_ROD_OUTER)
    tr_len = float(np.linalg.norm(TIE_ROD_OUTER - TIE_ROD_INNER))
    body_com = np.array([0.0, -HALF_TRACK, 0.25])  # on the vehicle centreline
    s = ""
    s += _link("ground", 0, [0, 0, 0], (0, 0, 0))
    s += _link("body", pr.body_mass, body_com, (100, 100, 100))
    s += _link("lower_arm", pr.lower_arm_mass, LOWER_ARM_COM - la_o,
               lower_arm_inertia(pr.lower_arm_mass))
    # hub + wheel ~ a disc about y; upper arm a small triangle
    s += _link("hub", pr.hub_mass, WHEEL_CENTRE - LOWER_BALL_JOINT, (1.2, 2.0, 1.2))
    s += _link("upper_arm", pr.upper_arm_mass, ua_com - ua_o, (0.012, 0.01, 0.02))
    # slender rod along y: I_perp = m L^2 / 12, I_axis = m r^2 / 2 with r = 10 mm
    i_perp = pr.tie_rod_mass * tr_len ** 2 / 12.0
    s += _link("tie_rod", pr.tie_rod_mass, tr_com - TIE_ROD_INNER,
               (i_perp, pr.tie_rod_mass * 1e-4 / 2.0, i_perp))
    s += _joint("body_z", "prismatic", "ground", "body", [0, 0, 0], "0 0 1")
    s += _joint("lower_arm_pivot", "revolute", "body", "lower_arm", la_o)
    s += _joint("lower_ball_joint", "spherical", "lower_arm", "hub", LOWER_BALL_JOINT - la_o)
    s += _joint("upper_arm_pivot", "revolute", "body", "upper_arm", ua_o)
    s += _joint("tie_rod_inner", "spherical", "body", "tie_rod", TIE_ROD_INNER)
    return f'<?xml version="1.0"?>\n<robot name="double_wishbone">\n{s}</robot>\n'
