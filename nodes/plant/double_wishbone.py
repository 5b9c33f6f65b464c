"""Realistic quarter car: a double-wishbone front corner of an MPV in PyBullet (thesis Ch. 4
Sec. 4.2, Table 4.2), closed kinematic loop and jounce bumper included.

Parts (Table 4.2): body M_b 535 kg on a vertical translational joint; lower arm 5 kg and upper
arm 2 kg on revolute joints (body bushes); hub (upright + wheel) 38.75 kg on a spherical joint
at the lower ball joint; tie rod 2 kg on a spherical joint at the rack. The loops are closed by
two PyBullet point-to-point constraints (``JOINT_POINT2POINT``): upper arm <-> hub at the upper
ball joint, tie rod <-> hub at the steering-arm ball joint. Mobility: body heave, suspension
travel, and the (inert) spin of the tie rod about its own axis.

Forces: the torsion spring K_theta = 46.74 N m/deg acts about the lower-arm pivot axis (a
torsion bar; applied as the revolute joint's torque, preloaded with the static torque tau_0);
the damper (c = 3800 N s/m, in the controller node) is a force actuator along the damper axis
between the body mount and the lower-arm mount; the jounce bumper (:mod:`.bump_stop`) pushes
the lower arm's pad down and the body up, along the body's vertical, once its clearance has
closed; the tyre force F_t (tyre node) is applied vertically at the wheel centre of the hub,
as the thesis applies it.

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

**Damper force convention**: ``F_d`` is the damper's axial force, compression-positive as a
force on the body (pushes the top mount up along the axis); the arm gets -F_d along the axis.
Its vertical component on the body is F_d cos(lean) = 0.998 F_d (lean 4.0 deg). Because
the damper moves at about MR = 0.62 of the wheel centre, the state also gives ``z_damper``
(compression from static) and ``v_damper`` (compression velocity, positive when the damper
shortens): a controller that computes F_d = c * v_damper with the physical c = 3800 N s/m
reproduces the thesis's damper; one that uses v_w - v_b should use an equivalent c_s instead
(1500 N s/m in Table 4.3; identified for this geometry by ``suscosim equivalent-lumped``,
docs/vehicles_roads.md).

**Bump-stop force** ``F_bs`` [N] (in ``plant/response``, via :meth:`extra_response`):
compression-positive, >= 0, the force the bumper applies on the body (upward) and on the
arm's pad (downward), from the state at the start of the step, as the torsion-bar torque.

**Arm accelerations** ``a_arm_{loc1,cg,loc2}_{x,y,z}`` [m/s^2] (in ``plant/response``, via
:meth:`response_velocities`): vehicle axes, of three points of the lower arm
(:data:`ARM_ACCEL_POINTS`: 20 mm inboard of the ball joint, the centre of mass, 20 mm
outboard of the bush midpoint; thesis Table 5.4's Loc1, CG, Loc2), computed as the plant
node computes a_b and a_w: the change of the point's velocity over the step's first substep
divided by its length.

**Arm loads** (``loads()["arm"]``): the loads ON the lower arm in the arm frame (origin at the
midpoint of the two body bushes, x along the pivot axis forward, y outward toward the ball
joint in the arm plane, z = x cross y; the frame turns with the arm), in N; see
:func:`arm_loads` for where each acts and how it is extracted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pybullet as p

from cosim import lower_arm as la

from .bump_stop import BumpStopParams, bump_stop_force, compression
from .model import GRAVITY, PlantModel
from .quarter_car_lumped import load_urdf_text, new_direct_client

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

_BS = BumpStopParams()


@dataclass(frozen=True)
class DoubleWishboneParams:
    """Table 4.2 (unladen MPV) and the jounce bumper (:mod:`.bump_stop`)."""

    body_mass: float = 535.0
    """M_b [kg]."""
    hub_mass: float = 38.75
    """M_h, upright and wheel [kg]."""
    lower_arm_mass: float = la.MASS_KG
    """M_la [kg]."""
    upper_arm_mass: float = 2.0
    """M_ua [kg]."""
    tie_rod_mass: float = 2.0
    """M_tr [kg]."""
    torsion_stiffness_nm_per_deg: float = 46.74
    """K_theta [N m/deg]."""
    bump_stop: bool = True
    """Fit the jounce bumper (``false`` removes it)."""
    bump_stop_clearance: float = _BS.clearance
    """g, bumper tip to pad at static ride height, along the body's vertical [m]."""
    bump_stop_initial_rate: float = _BS.initial_rate
    """k_0, bumper rate at first contact [N/m]."""
    bump_stop_stroke: float = _BS.stroke
    """s_b, bumper block compression [m]."""

    @property
    def k_theta(self) -> float:
        """K_theta [N m/rad]."""
        return self.torsion_stiffness_nm_per_deg * 180.0 / np.pi

    @property
    def unsprung_mass(self) -> float:
        """Hub + arms + tie rod [kg] (Table 4.3's m_w)."""
        return self.hub_mass + self.lower_arm_mass + self.upper_arm_mass + self.tie_rod_mass

    @property
    def bump_stop_params(self) -> BumpStopParams | None:
        """The bumper's parameters, or None without a bumper."""
        if not self.bump_stop:
            return None
        return BumpStopParams(clearance=self.bump_stop_clearance,
                              initial_rate=self.bump_stop_initial_rate,
                              stroke=self.bump_stop_stroke)


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


def _urdf(pr: DoubleWishboneParams) -> str:
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


def _rot(quat) -> np.ndarray:
    return np.array(p.getMatrixFromQuaternion(quat)).reshape(3, 3)


class DoubleWishboneCorner(PlantModel):
    """Double-wishbone front-left corner; one corner named "FL" on the left track."""

    n_corners = 1
    name = "quarter_car_double_wishbone"

    def __init__(self, params: DoubleWishboneParams | None = None,
                 static_dt: float = 1e-3) -> None:
        self.params = pr = params or DoubleWishboneParams()
        self.bump_stop = pr.bump_stop_params
        self.client = c = new_direct_client()
        p.setPhysicsEngineParameter(numSolverIterations=200, erp=0.2,
                                    solverResidualThreshold=1e-12, physicsClientId=c)
        self.body = b = load_urdf_text(_urdf(pr), c, useFixedBase=True,
                                       flags=p.URDF_USE_INERTIA_FROM_FILE)
        for j in range(p.getNumJoints(b, physicsClientId=c)):
            info = p.getJointInfo(b, j, physicsClientId=c)
            if info[2] == p.JOINT_SPHERICAL:
                p.setJointMotorControlMultiDof(b, j, p.POSITION_CONTROL, [0, 0, 0, 1],
                                               targetVelocity=[0, 0, 0], positionGain=0,
                                               velocityGain=0, force=[0, 0, 0],
                                               physicsClientId=c)
            else:
                p.setJointMotorControl2(b, j, p.VELOCITY_CONTROL, force=0, physicsClientId=c)
            p.changeDynamics(b, j, linearDamping=0, angularDamping=0, jointDamping=0,
                             physicsClientId=c)
            p.enableJointForceTorqueSensor(b, j, True, physicsClientId=c)
        ua_o = 0.5 * (UPPER_BUSH_FRONT + UPPER_BUSH_REAR)
        self._c_upper = p.createConstraint(
            b, UPPER_ARM, b, HUB, p.JOINT_POINT2POINT, [0, 0, 0],
            _local(b, UPPER_ARM, UPPER_BALL_JOINT - ua_o, c),
            _local(b, HUB, UPPER_BALL_JOINT - LOWER_BALL_JOINT, c), physicsClientId=c)
        self._c_tie = p.createConstraint(
            b, TIE_ROD, b, HUB, p.JOINT_POINT2POINT, [0, 0, 0],
            _local(b, TIE_ROD, TIE_ROD_OUTER - TIE_ROD_INNER, c),
            _local(b, HUB, TIE_ROD_OUTER - LOWER_BALL_JOINT, c), physicsClientId=c)
        for cid in (self._c_upper, self._c_tie):
            p.changeConstraint(cid, maxForce=1e9, physicsClientId=c)
        self._dt: float | None = None
        self._F_t = 0.0
        self._F_d = 0.0
        self._F_bs = 0.0
        self._tau = 0.0
        self._read()
        self._z_b0, self._z_w0, self._L0 = self._zb_abs, self._zw_abs, self._damper_len
        self._theta0 = self._theta
        self._pad_z0 = float(self._pad[2])
        self.tau0 = self._static_torque(static_dt)
        self._read()
        self._applied_pose = (self._R_arm, self._R_hub, self._u)

    # --- helpers ---
    def _read(self) -> None:
        c, b = self.client, self.body
        js = p.getJointStates(b, [BODY, LOWER_ARM], physicsClientId=c)
        self._zb_abs, self._vb = js[0][0], js[0][1]
        self._theta, self._omega = js[1][0], js[1][1]
        hub = p.getLinkState(b, HUB, computeLinkVelocity=1, computeForwardKinematics=1,
                             physicsClientId=c)
        self._zw_abs, self._vw = hub[0][2], hub[6][2]
        self._hub_pos = np.array(hub[0])
        self._R_hub = _rot(hub[5])
        body = p.getLinkState(b, BODY, computeLinkVelocity=1, computeForwardKinematics=1,
                              physicsClientId=c)
        arm = p.getLinkState(b, LOWER_ARM, computeLinkVelocity=1, computeForwardKinematics=1,
                             physicsClientId=c)
        self._R_arm = _rot(arm[5])
        self._arm_state = arm
        top = self._world(body, BODY, DAMPER_UPPER)
        bot = self._world(arm, LOWER_ARM, DAMPER_LOWER)
        self._pad = self._world(arm, LOWER_ARM, BUMP_STOP_PAD)
        d = top - bot
        self._damper_len = float(np.linalg.norm(d))
        self._u = d / self._damper_len  # unit vector arm mount -> body mount
        v_top = _point_velocity(body, top)
        v_bot = _point_velocity(arm, bot)
        self._v_damper = -float(self._u @ (v_top - v_bot))  # compression rate
        self._top, self._bot = top, bot

    def _world(self, link_state, link: int, corner_point: np.ndarray) -> np.ndarray:
        """World position of a hardpoint (given in the static corner frame) fixed to ``link``
        (``link_state`` from getLinkState with forward kinematics)."""
        pos, R = np.array(link_state[4]), _rot(link_state[5])
        local = self._link_local[link] @ np.append(corner_point, 1.0)
        return pos + R @ local

    @property
    def _link_local(self) -> dict[int, np.ndarray]:
        # link frame origins in the static corner frame (all link frames axis-aligned at t=0)
        if not hasattr(self, "_ll"):
            origins = {BODY: np.zeros(3), LOWER_ARM: 0.5 * (LOWER_BUSH_FRONT + LOWER_BUSH_REAR),
                       HUB: LOWER_BALL_JOINT, UPPER_ARM: 0.5 * (UPPER_BUSH_FRONT
                                                                + UPPER_BUSH_REAR),
                       TIE_ROD: TIE_ROD_INNER}
            self._ll = {k: np.hstack([np.eye(3), -o[:, None]]) for k, o in origins.items()}
        return self._ll

    def bump_stop_compression(self) -> float:
        """Bumper compression delta [m] in the current state (< 0: clearance still open):
        the pad's rise minus the body's rise minus the clearance (:mod:`.bump_stop`)."""
        if self.bump_stop is None:
            return -np.inf
        return compression(float(self._pad[2]) - self._pad_z0, self._zb_abs - self._z_b0,
                           self.bump_stop)

    def bump_stop_force(self) -> float:
        """Bumper force F_bs [N] (>= 0) in the current state: what the next substep applies."""
        if self.bump_stop is None:
            return 0.0
        return bump_stop_force(self.bump_stop_compression(), self.bump_stop)

    def _apply(self) -> None:
        c, b = self.client, self.body
        p.setJointMotorControl2(b, LOWER_ARM, p.TORQUE_CONTROL, force=self._tau,
                                physicsClientId=c)
        p.applyExternalForce(b, HUB, [0, 0, self._F_t], self._hub_pos.tolist(), p.WORLD_FRAME,
                             physicsClientId=c)
        f = self._F_d * self._u
        p.applyExternalForce(b, BODY, f.tolist(), self._top.tolist(), p.WORLD_FRAME,
                             physicsClientId=c)
        p.applyExternalForce(b, LOWER_ARM, (-f).tolist(), self._bot.tolist(), p.WORLD_FRAME,
                             physicsClientId=c)
        if self._F_bs > 0.0:  # bumper: up on the body, down on the arm's pad, at the pad
            pad = self._pad.tolist()
            p.applyExternalForce(b, BODY, [0.0, 0.0, self._F_bs], pad, p.WORLD_FRAME,
                                 physicsClientId=c)
            p.applyExternalForce(b, LOWER_ARM, [0.0, 0.0, -self._F_bs], pad, p.WORLD_FRAME,
                                 physicsClientId=c)

    def _static_torque(self, dt: float) -> float:
        """Static solve at build time: the torsion-bar preload tau_0 for which the assembled
        corner, carrying its static tyre load, has zero acceleration. The arm's angular
        acceleration is affine in the torque, so two trial steps from rest (state restored
        after each) give tau_0 exactly. (The bumper is clear at ride height: F_bs = 0.)"""
        c = self.client
        p.setTimeStep(dt, physicsClientId=c)
        sid = p.saveState(physicsClientId=c)
        W = float(self.static_tyre_load()[0])
        omegas = []
        trials = (0.0, 1000.0)
        for tau in trials:
            p.restoreState(sid, physicsClientId=c)
            self._read()
            self._F_t, self._F_d, self._F_bs, self._tau = W, 0.0, 0.0, tau
            self._apply()
            p.stepSimulation(physicsClientId=c)
            omegas.append(p.getJointState(self.body, LOWER_ARM, physicsClientId=c)[1])
        p.restoreState(sid, physicsClientId=c)
        p.removeState(sid, physicsClientId=c)
        self._dt = dt
        return trials[0] - omegas[0] * (trials[1] - trials[0]) / (omegas[1] - omegas[0])

    # --- PlantModel ---
    def static_tyre_load(self) -> np.ndarray:
        pr = self.params
        return np.array([(pr.body_mass + pr.unsprung_mass) * GRAVITY])

    def state(self) -> dict[str, np.ndarray]:
        return {
            "z_b": np.array([self._zb_abs - self._z_b0]), "v_b": np.array([self._vb]),
            "z_w": np.array([self._zw_abs - self._z_w0]), "v_w": np.array([self._vw]),
            "z_damper": np.array([self._L0 - self._damper_len]),
            "v_damper": np.array([self._v_damper]),
            "arm_angle": np.array([self._theta - self._theta0]),
        }

    def spring_force(self) -> np.ndarray:
        """Dynamic torsion-bar torque expressed as a vertical force at the ball joint,
        K_theta (theta - theta_0) / L with L = :func:`cosim.lower_arm.lever_ball_joint`
        (0.294 m), upward on the body [N]."""
        return np.array([self.params.k_theta * (self._theta - self._theta0)
                         / la.lever_ball_joint()])

    def extra_response(self) -> dict[str, np.ndarray]:
        """``F_bs``: the jounce-bumper force [N] (>= 0) the next substep applies."""
        return {"F_bs": np.array([self.bump_stop_force()])}

    def response_velocities(self) -> dict[str, np.ndarray]:
        """World (vehicle-axes) velocities [m/s] of the lower arm's points
        :data:`ARM_ACCEL_POINTS` in the current state, keyed by the acceleration fields the
        plant node derives from them: ``a_arm_{loc1,cg,loc2}_{x,y,z}`` (x forward, y left,
        z up; kinematic acceleration, gravity not included, 0 at static equilibrium). Each
        velocity is that of the material point at its current position, v_com + omega x
        (r - r_com), from the arm's link state that :meth:`_read` already fetched (no
        PyBullet call: the dynamics are untouched)."""
        arm = self._arm_state
        out: dict[str, np.ndarray] = {}
        for name, pt in ARM_ACCEL_POINTS.items():
            v = _point_velocity(arm, self._world(arm, LOWER_ARM, la.to_corner(pt)))
            for axis, val in zip("xyz", v, strict=True):
                out[f"a_arm_{name}_{axis}"] = np.array([float(val)])
        return out

    def substep(self, dt: float, F_t: np.ndarray, F_d: np.ndarray) -> None:
        if dt != self._dt:
            p.setTimeStep(dt, physicsClientId=self.client)
            self._dt = dt
        self._F_t, self._F_d = float(F_t[0]), float(F_d[0])
        self._tau = self.tau0 - self.params.k_theta * (self._theta - self._theta0)
        self._F_bs = self.bump_stop_force()
        # the pose the forces of this substep are applied (and the joint sensors evaluated) in
        self._applied_pose = (self._R_arm, self._R_hub, self._u)
        self._apply()
        p.stepSimulation(physicsClientId=self.client)
        self._read()

    def loads(self) -> dict[str, dict[str, float]]:
        return {"arm": arm_loads(self)}

    def info(self) -> dict[str, object]:
        d = super().info()
        bs = self.bump_stop
        d.update({"model": self.name, "corner_names": ["FL"], "wheel_x": [0.0],
                  "wheel_track": [0], "unsprung_mass": [self.params.unsprung_mass],
                  "torsion_preload_nm": self.tau0,
                  "arm_points": {k: [float(x) for x in to_arm_frame(v)]
                                 for k, v in ARM_POINTS.items()},
                  "bump_stop": None if bs is None else {
                      "clearance_m": bs.clearance, "initial_rate_n_per_m": bs.initial_rate,
                      "stroke_m": bs.stroke}})
        return d

    def close(self) -> None:
        if p.isConnected(self.client):
            p.disconnect(self.client)


def _point_velocity(link_state, world_point: np.ndarray) -> np.ndarray:
    """World velocity of a point fixed to a link (``link_state`` with velocity and forward
    kinematics): v_com + omega x (r - r_com)."""
    v, w, com = np.array(link_state[6]), np.array(link_state[7]), np.array(link_state[0])
    return v + np.cross(w, world_point - com)


def _local(body: int, link: int, offset_from_link_origin: np.ndarray, client: int) -> list:
    """Constraint pivots are given relative to the link's centre of mass frame in PyBullet."""
    ls = p.getLinkState(body, link, physicsClientId=client)
    local_inertial_pos = np.array(ls[2])
    return (np.asarray(offset_from_link_origin) - local_inertial_pos).tolist()


def arm_loads(model: DoubleWishboneCorner) -> dict[str, float]:
    """Loads ON the lower arm during the latest substep, in the arm frame (which turns with
    the arm) at the start of that substep, t_k [N, N m].

    Where each acts (arm-frame points: :data:`cosim.lower_arm.HARDPOINTS`):

    * ``ball_joint_{x,y,z}``: force from the hub at the ball joint;
    * ``damper_mount_{x,y,z}``: force from the damper at its seat, -F_d along the damper axis;
    * ``bush_front_{x,y,z}``, ``bush_rear_{x,y,z}``: forces from the body at the two bush
      centres;
    * ``bump_stop_y``, ``bump_stop_z``: force from the jounce bumper at the pad
      (``BUMP_STOP_PAD``): (0, 0, -F_bs) in world axes, i.e. ``bump_stop_z`` = -F_bs cos(theta)
      <= 0 (pushes the arm down) and ``bump_stop_y`` = -F_bs sin(theta) for an arm turned by
      theta (jounce positive); its arm-frame x component is zero (the arm turns about x and
      the body only heaves). Both are 0 while the bumper is clear;
    * ``torsion_bar_mx`` [N m]: the torsion-spring moment about the arm's x axis (static
      preload included). It is a pure moment; it enters the arm through its pivot, half at each
      bush eye (:data:`cosim.lower_arm.TORSION_SPRING_POINTS`, as the thesis split its
      revolute joint's loads over nodes A and B); for the rigid arm's balance its point does
      not matter, for the FE it does.

    These loads and the arm's weight are in equilibrium with its inertia: sum F + m g =
    m a_com and sum (r x F) + M_x e_x = d(H)/dt (tested, static and in bumper contact, in
    tests/vehicles/test_double_wishbone.py).

    Extraction:

    * PyBullet's joint force-torque sensor (``enableJointForceTorqueSensor``,
      ``getJointState(...)[2]``; ``getJointStateMultiDof`` for spherical joints) reports the
      wrench that the **parent exerts on the child**, in the **child link frame**, the moment
      taken about the child's **centre of mass**, with the joint motor torque included. It
      includes the forces of the loop-closing POINT2POINT constraints. The child frame is
      the one at the **start** of the substep (where the step's forces are evaluated), so
      every load is rotated with the arm's and hub's orientation at t_k, the time the loads
      belong to (the orientation after the step misplaces them by omega dt: 0.2 % of the
      joint forces at 4 rad/s and 0.5 ms, enough to spoil the dynamic balance).
    * ball joint: minus the lower-ball-joint sensor wrench's force (parent arm -> child hub),
      rotated from the hub frame to the arm frame;
    * damper mount and bump stop: the actuator forces we applied in that substep;
    * bushes: the lower-arm pivot sensor wrench (body -> arm), moved to the arm-frame origin
      (midpoint of the bushes): F, M_O = M_com + r_com x F. With the bushes at x = +-d/2 on the
      pivot axis, the moments about y and z split the force between them:
      F_front,z = F_z/2 - M_y/d, F_rear,z = F_z/2 + M_y/d, F_front,y = F_y/2 + M_z/d,
      F_rear,y = F_y/2 - M_z/d; the axial force F_x is shared equally (statically
      indeterminate between two bushes of equal stiffness). M_x is the torsion-bar moment.
    (``getConstraintState`` of a POINT2POINT returns the 3 force components the constraint
    applies on its child body B, world axes; it is not needed here.)
    """
    c, b = model.client, model.body
    R_af = arm_frame()[1]
    R_arm, R_hub, u = model._applied_pose  # the pose at the start of the substep
    to_arm = R_af.T @ R_arm.T  # world -> arm frame
    r_com = np.array(p.getLinkState(b, LOWER_ARM, physicsClientId=c)[2])  # in the link frame

    w_pivot = np.array(p.getJointState(b, LOWER_ARM, physicsClientId=c)[2])
    F_link = w_pivot[:3]
    M_link = w_pivot[3:] + np.cross(r_com, F_link)  # about the link origin = O
    F = R_af.T @ F_link
    M = R_af.T @ M_link
    d = float(np.linalg.norm(LOWER_BUSH_FRONT - LOWER_BUSH_REAR))
    front = np.array([F[0] / 2, F[1] / 2 + M[2] / d, F[2] / 2 - M[1] / d])
    rear = np.array([F[0] / 2, F[1] / 2 - M[2] / d, F[2] / 2 + M[1] / d])

    w_bj = np.array(p.getJointStateMultiDof(b, HUB, physicsClientId=c)[2])
    ball = to_arm @ (-(R_hub @ w_bj[:3]))
    damper = to_arm @ (-model._F_d * u)
    bump = to_arm @ np.array([0.0, 0.0, -model._F_bs])

    out: dict[str, float] = {}
    for name, f in (("ball_joint", ball), ("damper_mount", damper), ("bush_front", front),
                    ("bush_rear", rear)):
        for axis, v in zip("xyz", f, strict=True):
            out[f"{name}_{axis}"] = float(v)
    out["bump_stop_y"] = float(bump[1])
    out["bump_stop_z"] = float(bump[2])
    out["torsion_bar_mx"] = float(M[0])
    return out
