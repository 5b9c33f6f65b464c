"""Realistic quarter car: a double-wishbone front corner of an MPV in PyBullet (thesis Ch. 4
Sec. 4.2, Table 4.2), closed kinematic loop included.

Parts (Table 4.2): body M_b 535 kg on a vertical translational joint; lower arm 5 kg and upper
arm 2 kg on revolute joints (body bushes); hub (upright + wheel) 38.75 kg on a spherical joint
at the lower ball joint; tie rod 2 kg on a spherical joint at the rack. The loops are closed by
two PyBullet point-to-point constraints (``JOINT_POINT2POINT``): upper arm <-> hub at the upper
ball joint, tie rod <-> hub at the steering-arm ball joint. Mobility: body heave, suspension
travel, and the (inert) spin of the tie rod about its own axis.

Forces: the torsion spring K_theta = 46.74 N m/deg acts about the lower-arm pivot axis (a
torsion bar; applied as the revolute joint's torque, preloaded with the static torque tau_0);
the damper (c = 3800 N s/m, in the controller node) is a force actuator along the damper axis
between the body mount and the lower-arm mount; the tyre force F_t (tyre node) is applied
vertically at the wheel centre of the hub, as the thesis applies it.

**Hardpoints** (the thesis gives none; plausible values for a small MPV, our reasoning):
corner frame = vehicle axes (x forward, y left, z up) with origin at the static wheel centre
of this **front-left** corner (outboard = +y, so the arm frame below has z up).

* the lower arm is the fatigue worker's arm (``nodes/fatigue/arm_geometry.py``: bushes
  +-0.16 m on the pivot axis, ball joint (0.03, 0.37, 0), damper seat (0.02, 0.225, 0) in the
  arm frame, flat arm). We place its frame at (0, -0.43, -0.13) in the corner frame with axes
  parallel to the corner frame (pivot axis along x: no anti-dive; arm plane horizontal at
  static ride height), so the ball joint is 60 mm inboard of and 130 mm below the wheel
  centre (inside the wheel rim); ``tests/vehicles/test_arm_geometry_consistent.py`` checks the
  numbers agree;
* consequences: arm lever 0.37 m, so the wheel rate is about K_theta / 0.37^2 ~ 20 kN/m, below
  the Table 4.3 31 kN/m (which needs a 0.294 m lever); damper motion ratio 0.225/0.37 = 0.61,
  close to the sqrt(1500/3800) = 0.63 that Table 4.3 implies;
* damper: lower mount = the arm's seat (0.02, -0.205, -0.13), top mount (0.02, -0.25, 0.40):
  4.9 deg inboard lean;
* upper arm: shorter (0.24 m, camber gain), bushes at y = -0.34, z = 0.22, x = +-0.11; ball
  joint at (0, -0.10, 0.20): kingpin inclination 6.9 deg, caster 5.2 deg;
* tie rod 0.32 m long, 0.14 m behind the axle at z = -0.03 (rear steer), rack end y = -0.40.
  Bump steer was not tuned;
* half track 0.7055 m (t = 1.411 m, Ch. 4 extraction); the body's centre of mass is put on the
  vehicle centreline (it only moves vertically, so its position has no effect).

**Damper force convention**: ``F_d`` is the damper's axial force, compression-positive as a
force on the body (pushes the top mount up along the axis); the arm gets -F_d along the axis.
Its vertical component on the body is F_d * cos(lean) = 0.996 F_d (lean 4.9 deg). Because
the damper moves at about MR = 0.61 of the wheel, the state also gives ``z_damper``
(compression from static) and ``v_damper`` (compression velocity, positive when the damper
shortens): a controller that computes F_d = c * v_damper with the physical c = 3800 N s/m
reproduces the thesis's damper; one that uses v_w - v_b should use an equivalent c_s instead
(1500 N s/m in Table 4.3; 1250 N s/m identified for this geometry, docs/vehicles_roads.md).

**Arm loads** (``loads()["arm"]``): forces ON the lower arm, in the arm frame (origin at the
midpoint of the two body bushes, x along the pivot axis forward, y outward toward the ball
joint in the arm plane, z = x cross y), in N:
``ball_joint_{x,y,z}`` from the hub, ``damper_mount_{x,y,z}`` from the damper,
``bush_front_{x,y,z}`` and ``bush_rear_{x,y,z}`` from the body; plus ``torsion_bar_mx`` [N m],
the torsion-bar moment on the arm about its x axis (static preload included).
Extraction method: see :meth:`DoubleWishboneCorner.loads`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pybullet as p

from .model import GRAVITY, PlantModel
from .quarter_car_lumped import load_urdf_text, new_direct_client

# ---- hardpoints in the corner frame [m] (see module docstring) ----
WHEEL_CENTRE = np.array([0.0, 0.0, 0.0])
ARM_ORIGIN = np.array([0.0, -0.43, -0.13])
"""Lower-arm frame origin (bush midpoint) in the corner frame; arm axes = corner axes."""
# lower arm = fatigue worker's arm_geometry (arm frame) + ARM_ORIGIN
LOWER_BUSH_FRONT = ARM_ORIGIN + np.array([0.160, 0.0, 0.0])
LOWER_BUSH_REAR = ARM_ORIGIN + np.array([-0.160, 0.0, 0.0])
LOWER_BALL_JOINT = ARM_ORIGIN + np.array([0.030, 0.370, 0.0])
DAMPER_LOWER = ARM_ORIGIN + np.array([0.020, 0.225, 0.0])
DAMPER_UPPER = np.array([0.02, -0.25, 0.40])
UPPER_BUSH_FRONT = np.array([0.11, -0.34, 0.22])
UPPER_BUSH_REAR = np.array([-0.11, -0.34, 0.22])
UPPER_BALL_JOINT = np.array([0.0, -0.10, 0.20])
TIE_ROD_INNER = np.array([-0.14, -0.40, -0.03])
TIE_ROD_OUTER = np.array([-0.14, -0.08, -0.03])
HALF_TRACK = 0.7055


def arm_frame() -> tuple[np.ndarray, np.ndarray]:
    """(origin, R): the lower-arm frame in the corner frame; columns of R are the arm's x, y, z
    axes, so p_arm = R.T @ (p_corner - origin)."""
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
}
"""The lower arm's load points (corner frame); :func:`to_arm_frame` gives them in the arm frame
(the numbers the fatigue worker's FE uses)."""


@dataclass(frozen=True)
class DoubleWishboneParams:
    """Table 4.2 (unladen MPV)."""

    body_mass: float = 535.0
    hub_mass: float = 38.75
    lower_arm_mass: float = 5.0
    upper_arm_mass: float = 2.0
    tie_rod_mass: float = 2.0
    torsion_stiffness_nm_per_deg: float = 46.74

    @property
    def k_theta(self) -> float:
        """K_theta [N m/rad]."""
        return self.torsion_stiffness_nm_per_deg * 180.0 / np.pi

    @property
    def unsprung_mass(self) -> float:
        return self.hub_mass + self.lower_arm_mass + self.upper_arm_mass + self.tie_rod_mass


def _fmt(v) -> str:
    return " ".join(f"{float(x):.9g}" for x in v)


def _link(name, m, com, inertia):
    return (f' <link name="{name}"><inertial><origin xyz="{_fmt(com)}"/><mass value="{m}"/>'
            f'<inertia ixx="{inertia[0]}" iyy="{inertia[1]}" izz="{inertia[2]}" ixy="0" '
            f'ixz="0" iyz="0"/></inertial></link>\n')


def _joint(name, kind, parent, child, origin, axis="1 0 0"):
    return (f' <joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{_fmt(origin)}"/><axis xyz="{axis}"/>'
            f'<limit lower="-3" upper="3" effort="1e12" velocity="1e6"/></joint>\n')


# link indices (joint index = child link index)
BODY, LOWER_ARM, HUB, UPPER_ARM, TIE_ROD = 0, 1, 2, 3, 4


def _urdf(pr: DoubleWishboneParams) -> str:
    la_o = 0.5 * (LOWER_BUSH_FRONT + LOWER_BUSH_REAR)
    ua_o = 0.5 * (UPPER_BUSH_FRONT + UPPER_BUSH_REAR)
    la_com = (LOWER_BUSH_FRONT + LOWER_BUSH_REAR + LOWER_BALL_JOINT) / 3.0
    ua_com = (UPPER_BUSH_FRONT + UPPER_BUSH_REAR + UPPER_BALL_JOINT) / 3.0
    tr_com = 0.5 * (TIE_ROD_INNER + TIE_ROD_OUTER)
    tr_len = float(np.linalg.norm(TIE_ROD_OUTER - TIE_ROD_INNER))
    body_com = np.array([0.0, -HALF_TRACK, 0.25])  # on the vehicle centreline
    s = ""
    s += _link("ground", 0, [0, 0, 0], (0, 0, 0))
    s += _link("body", pr.body_mass, body_com, (100, 100, 100))
    # lower arm: triangular plate ~0.34 x 0.30 m; upper arm smaller; hub+wheel ~ a disc
    s += _link("lower_arm", pr.lower_arm_mass, la_com - la_o, (0.05, 0.04, 0.09))
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


class DoubleWishboneCorner(PlantModel):
    """Double-wishbone front-left corner; one corner named "FL" on the left track."""

    n_corners = 1
    name = "quarter_car_double_wishbone"

    def __init__(self, params: DoubleWishboneParams | None = None,
                 static_dt: float = 1e-3) -> None:
        self.params = pr = params or DoubleWishboneParams()
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
        self._tau = 0.0
        self._read()
        self._z_b0, self._z_w0, self._L0 = self._zb_abs, self._zw_abs, self._damper_len
        self._theta0 = self._theta
        self.tau0 = self._static_torque(static_dt)
        self._read()

    # --- helpers ---
    def _read(self) -> None:
        c, b = self.client, self.body
        js = p.getJointStates(b, [BODY, LOWER_ARM], physicsClientId=c)
        self._zb_abs, self._vb = js[0][0], js[0][1]
        self._theta, self._omega = js[1][0], js[1][1]
        hub = p.getLinkState(b, HUB, computeLinkVelocity=1, physicsClientId=c)
        self._zw_abs, self._vw = hub[0][2], hub[6][2]
        self._hub_pos = np.array(hub[0])
        top = self._world(BODY, DAMPER_UPPER)
        bot = self._world(LOWER_ARM, DAMPER_LOWER)
        d = top - bot
        self._damper_len = float(np.linalg.norm(d))
        self._u = d / self._damper_len  # unit vector arm mount -> body mount
        v_top = self._point_velocity(BODY, top)
        v_bot = self._point_velocity(LOWER_ARM, bot)
        self._v_damper = -float(self._u @ (v_top - v_bot))  # compression rate
        self._top, self._bot = top, bot

    def _world(self, link: int, corner_point: np.ndarray) -> np.ndarray:
        """World position of a hardpoint (given in the static corner frame) fixed to ``link``."""
        ls = p.getLinkState(self.body, link, computeForwardKinematics=1,
                            physicsClientId=self.client)
        pos, orn = np.array(ls[4]), ls[5]
        R = np.array(p.getMatrixFromQuaternion(orn)).reshape(3, 3)
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

    def _point_velocity(self, link: int, world_point: np.ndarray) -> np.ndarray:
        ls = p.getLinkState(self.body, link, computeLinkVelocity=1,
                            computeForwardKinematics=1, physicsClientId=self.client)
        v, w, com = np.array(ls[6]), np.array(ls[7]), np.array(ls[0])
        return v + np.cross(w, world_point - com)

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

    def _static_torque(self, dt: float) -> float:
        """Static solve at build time: the torsion-bar preload tau_0 for which the assembled
        corner, carrying its static tyre load, has zero acceleration. The arm's angular
        acceleration is affine in the torque, so two trial steps from rest (state restored
        after each) give tau_0 exactly."""
        c = self.client
        p.setTimeStep(dt, physicsClientId=c)
        sid = p.saveState(physicsClientId=c)
        W = float(self.static_tyre_load()[0])
        omegas = []
        trials = (0.0, 1000.0)
        for tau in trials:
            p.restoreState(sid, physicsClientId=c)
            self._read()
            self._F_t, self._F_d, self._tau = W, 0.0, tau
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
        """Dynamic torsion-bar torque expressed as a vertical force at the wheel centre
        (K_theta (theta - theta_0) / lever, lever = 0.37 m, the arm's), upward on the body."""
        return np.array([self.params.k_theta * (self._theta - self._theta0) / 0.37])

    def substep(self, dt: float, F_t: np.ndarray, F_d: np.ndarray) -> None:
        if dt != self._dt:
            p.setTimeStep(dt, physicsClientId=self.client)
            self._dt = dt
        self._F_t, self._F_d = float(F_t[0]), float(F_d[0])
        self._tau = self.tau0 - self.params.k_theta * (self._theta - self._theta0)
        self._apply()
        p.stepSimulation(physicsClientId=self.client)
        self._read()

    def loads(self) -> dict[str, dict[str, float]]:
        return {"arm": arm_loads(self)}

    def info(self) -> dict[str, object]:
        d = super().info()
        d.update({"model": self.name, "corner_names": ["FL"], "wheel_x": [0.0],
                  "wheel_track": [0], "unsprung_mass": [self.params.unsprung_mass],
                  "torsion_preload_nm": self.tau0,
                  "arm_points": {k: [float(x) for x in to_arm_frame(v)]
                                 for k, v in ARM_POINTS.items()}})
        return d

    def close(self) -> None:
        if p.isConnected(self.client):
            p.disconnect(self.client)


def _local(body: int, link: int, offset_from_link_origin: np.ndarray, client: int) -> list:
    """Constraint pivots are given relative to the link's centre of mass frame in PyBullet."""
    ls = p.getLinkState(body, link, physicsClientId=client)
    local_inertial_pos = np.array(ls[2])
    return (np.asarray(offset_from_link_origin) - local_inertial_pos).tolist()


def arm_loads(model: DoubleWishboneCorner) -> dict[str, float]:
    """Forces ON the lower arm in the arm frame [N] (and the torsion-bar moment [N m]).

    Extraction (verified in tests/vehicles/test_double_wishbone.py by the arm's equilibrium):

    * PyBullet's joint force-torque sensor (``enableJointForceTorqueSensor``,
      ``getJointState(...)[2]``; ``getJointStateMultiDof`` for spherical joints) reports the
      wrench that the **parent exerts on the child**, in the **child link frame**, the moment
      taken about the child's **centre of mass**, with the joint motor torque included. It
      includes the forces of the loop-closing POINT2POINT constraints.
    * ball joint: minus the lower-ball-joint sensor wrench's force (parent arm -> child hub),
      rotated from the hub frame to the arm frame;
    * damper mount: -F_d along the damper axis (the actuator force we apply);
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
    arm = p.getLinkState(b, LOWER_ARM, computeForwardKinematics=1, physicsClientId=c)
    R_arm = np.array(p.getMatrixFromQuaternion(arm[5])).reshape(3, 3)
    hub = p.getLinkState(b, HUB, computeForwardKinematics=1, physicsClientId=c)
    R_hub = np.array(p.getMatrixFromQuaternion(hub[5])).reshape(3, 3)
    to_arm = R_af.T @ R_arm.T  # world -> arm frame

    w_pivot = np.array(p.getJointState(b, LOWER_ARM, physicsClientId=c)[2])
    F_link = w_pivot[:3]
    M_link = w_pivot[3:] + np.cross(np.array(arm[2]), F_link)  # about the link origin = O
    F = R_af.T @ F_link
    M = R_af.T @ M_link
    d = float(np.linalg.norm(LOWER_BUSH_FRONT - LOWER_BUSH_REAR))
    front = np.array([F[0] / 2, F[1] / 2 + M[2] / d, F[2] / 2 - M[1] / d])
    rear = np.array([F[0] / 2, F[1] / 2 - M[2] / d, F[2] / 2 + M[1] / d])

    w_bj = np.array(p.getJointStateMultiDof(b, HUB, physicsClientId=c)[2])
    ball = to_arm @ (-(R_hub @ w_bj[:3]))
    damper = to_arm @ (-model._F_d * model._u)

    out: dict[str, float] = {}
    for name, f in (("ball_joint", ball), ("damper_mount", damper), ("bush_front", front),
                    ("bush_rear", rear)):
        for axis, v in zip("xyz", f, strict=True):
            out[f"{name}_{axis}"] = float(v)
    out["torsion_bar_mx"] = float(M[0])
    return out
