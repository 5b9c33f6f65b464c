"""Realistic quarter car: a double-wishbone front corner of an MPV in PyBullet (thesis Ch. 4
Sec. 4.2, Table 4.2), closed kinematic loop and jounce bumper included; its hardpoints:
:mod:`.double_wishbone_geometry` (the thesis gives none; ours and their reasoning there).

Parts (Table 4.2): body M_b 535 kg on a vertical translational joint; lower arm 5 kg and upper
arm 2 kg on revolute joints (body bushes); hub (upright + wheel) 38.75 kg on a spherical joint
at the lower ball joint; tie rod 2 kg on a spherical joint at the rack. Two PyBullet
``JOINT_POINT2POINT`` constraints close the loops: upper arm <-> hub at the upper ball joint,
tie rod <-> hub at the steering-arm ball joint. Mobility: body heave, suspension travel, the
(inert) spin of the tie rod about its axis.

Forces: the torsion spring K_theta = 46.74 N m/deg about the lower-arm pivot axis (a torsion
bar: the revolute joint's torque, preloaded with the static torque tau_0); the damper (c =
3800 N s/m, in the controller node) along its axis between the body mount and the lower-arm
mount; the jounce bumper (:mod:`.bump_stop`) down on the arm's pad and up on the body, along
the body's vertical, once its clearance has closed (``F_bs`` [N] >= 0 in ``plant/response``,
from the state at the step's start); the tyre force F_t (tyre node) vertical at the wheel
centre, as the thesis applies it.

**Damper force convention**: ``F_d`` is the damper's axial force, compression-positive on the
body (the arm gets -F_d along the axis; vertical share cos 4.0 deg = 0.998). The damper moves
at about MR = 0.62 of the wheel centre, so the state also gives ``z_damper`` and ``v_damper``
(compression, positive when it shortens): F_d = c v_damper with the physical c = 3800 N s/m
is the thesis's damper; a law on v_w - v_b needs an equivalent c_s (Table 4.3: 1500 N s/m;
``suscosim equivalent-lumped``, docs/vehicles_roads.md).

``plant/response`` also carries ``a_arm_{loc1,cg,loc2}_{x,y,z}`` [m/s^2], vehicle axes, of the
lower arm's points :attr:`.CornerGeometry.arm_accel_points` (thesis Table 5.4's Loc1, CG,
Loc2; :meth:`response_velocities`). ``loads()``: the loads ON the lower arm in its arm frame
(:func:`.arm_loads.arm_loads`) and ON the upper arm (:mod:`.upper_arm_loads`) [N, N m].
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, fields

import numpy as np

from cosim import corner as corner_file
from cosim import lower_arm as la
from cosim.corner import Corner

from .arm_loads import arm_loads_later
from .bump_stop import BumpStopParams, bump_stop_force, compression
from .double_wishbone_geometry import BODY, HUB, LOWER_ARM, TIE_ROD, UPPER_ARM, CornerGeometry
from .model import GRAVITY, PlantModel
from .point_kinematics import point_velocity
from .quarter_car_lumped import load_urdf_text, new_direct_client, release_joint
from .quarter_car_lumped import quat_matrix as _rot
from .quiet_pybullet import p
from .upper_arm_loads import upper_arm_frame, upper_arm_loads_later

_BS = BumpStopParams()
_READ_LINKS = [HUB, BODY, LOWER_ARM, UPPER_ARM]
"""The links whose states each substep reads (:meth:`DoubleWishboneCorner._read`)."""


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
    bump_stop_transition: float = _BS.transition
    """r, fraction of s_b beyond which the law goes on along its tangent [-] (0 < r < 1)."""

    @classmethod
    def from_corner(cls, c: Corner) -> DoubleWishboneParams:
        """The parameters a corner file gives (masses, torsion bar, bumper)."""
        kw = {f"{k}_mass": c.masses[k] for k in ("body", "hub", "lower_arm", "upper_arm",
                                                  "tie_rod")}
        kw.update({f"bump_stop_{k}": v for k, v in (c.bump_stop or {}).items()})
        return cls(torsion_stiffness_nm_per_deg=c.torsion_bar_nm_per_deg,
                   bump_stop=c.bump_stop is not None, **kw)

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
        return BumpStopParams(**{f.name: getattr(self, f"bump_stop_{f.name}")
                                 for f in fields(BumpStopParams)})


class DoubleWishboneCorner(PlantModel):
    """Double-wishbone front-left corner; one corner named "FL" on the left track."""

    n_corners = 1
    name = "quarter_car_double_wishbone"

    def __init__(self, params: DoubleWishboneParams | None = None,
                 static_dt: float = 1e-3, corner: Corner | None = None) -> None:
        """``corner``: the corner file (:mod:`cosim.corner`; default the built-in MPV corner)
        whose hardpoints make the model; ``params``: its masses, torsion bar and bumper
        (default: the corner file's, :meth:`DoubleWishboneParams.from_corner`)."""
        self.corner = cf = corner or corner_file.builtin()
        if cf.coil_n_per_m > 0.0:
            raise ValueError(f"{cf.source}: the PyBullet corner has no coil spring yet "
                             "(spring.coil_n_per_m): use a torsion bar")
        self.geom = g = CornerGeometry(cf)
        self.params = pr = params or DoubleWishboneParams.from_corner(cf)
        if pr.bump_stop and g.bump_stop_pad is None:
            raise ValueError(f"{cf.source}: a bump stop needs hardpoints.bump_stop_pad")
        self.bump_stop = pr.bump_stop_params
        self._k_theta = pr.k_theta  # [N m/rad]
        self.client = c = new_direct_client()
        p.setPhysicsEngineParameter(numSolverIterations=200, erp=0.2,
                                    solverResidualThreshold=1e-12, physicsClientId=c)
        self.body = b = load_urdf_text(g.urdf(pr), c, useFixedBase=True,
                                       flags=p.URDF_USE_INERTIA_FROM_FILE)
        for j in range(p.getNumJoints(b, physicsClientId=c)):
            release_joint(b, j, c)
            p.changeDynamics(b, j, linearDamping=0, angularDamping=0, jointDamping=0,
                             physicsClientId=c)
        self._arm_r_com = p.getLinkState(b, LOWER_ARM, physicsClientId=c)[2]
        # the upper arm's loads (nodes/plant/upper_arm_loads.py): its centre of mass in its
        # link frame, its frame's axes in the link frame (link axes = corner axes at rest; by
        # rows too), the bush spacing
        self._ua_r_com = p.getLinkState(b, UPPER_ARM, physicsClientId=c)[2]
        self._ua_frame_rows = upper_arm_frame(cf)[1].tolist()
        self._ua_spacing = float(np.linalg.norm(g.upper_bush_front - g.upper_bush_rear))
        ua_o = 0.5 * (g.upper_bush_front + g.upper_bush_rear)
        self._c_upper = p.createConstraint(
            b, UPPER_ARM, b, HUB, p.JOINT_POINT2POINT, [0, 0, 0],
            _local(b, UPPER_ARM, g.upper_ball_joint - ua_o, c),
            _local(b, HUB, g.upper_ball_joint - g.lower_ball_joint, c), physicsClientId=c)
        self._c_tie = p.createConstraint(
            b, TIE_ROD, b, HUB, p.JOINT_POINT2POINT, [0, 0, 0],
            _local(b, TIE_ROD, g.tie_rod_outer - g.tie_rod_inner, c),
            _local(b, HUB, g.tie_rod_outer - g.lower_ball_joint, c), physicsClientId=c)
        for cid in (self._c_upper, self._c_tie):
            p.changeConstraint(cid, maxForce=1e9, physicsClientId=c)
        # hardpoints in their links' frames (fixed): the damper mounts, the bumper pad, the
        # points whose accelerations plant/response carries
        self._loc_top = _link_point(np.zeros(3), g.damper_upper)  # on the body
        self._body_quat: tuple[float, ...] | None = None  # the body's, at the last read
        # on the arm (one batched product a read): the damper's seat, the pad (no bumper:
        # the ball joint's place, unused), then the points whose rates plant/response carries
        o = 0.5 * (g.lower_bush_front + g.lower_bush_rear)
        self._arm_locals = np.array([_link_point(o, pt) for pt in (
            g.damper_lower, g.lower_ball_joint if g.bump_stop_pad is None else g.bump_stop_pad,
            *(g.to_corner(q) for q in g.arm_accel_points.values()))]).reshape(-1, 3, 1)
        self._accel_names = [tuple(f"a_arm_{name}_{axis}" for axis in "xyz")
                             for name in g.arm_accel_points]
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
        self._applied_pose = (self._R_arm, self._hub_quat, self._u)
        self._ua_quat_applied = self._ua_quat

    # --- helpers ---
    def _read(self) -> None:
        """Read the links' states after a substep (:mod:`.point_kinematics`: plain floats
        where the bits allow; the arm's points in one batched rotation)."""
        c, b = self.client, self.body
        js = p.getJointStates(b, [BODY, LOWER_ARM], physicsClientId=c)
        self._zb_abs, self._vb = js[0][0], js[0][1]
        self._theta = js[1][0]
        self._w_pivot = js[1][2]  # the arm pivot's sensor wrench: the arm loads
        # one call for the links: the forward kinematics computed once
        hub, body, arm, ua = p.getLinkStates(b, _READ_LINKS, computeLinkVelocity=1,
                                             computeForwardKinematics=1, physicsClientId=c)
        self._ua_quat = ua[5]  # the upper arm's rotation: for its loads
        self._zw_abs, self._vw = hub[0][2], hub[6][2]
        self._hub_pos = hub[0]
        self._hub_quat = hub[5]  # its rotation only when the arm loads need it
        self._R_arm = R_arm = _rot(arm[5])
        self._arm_state = arm
        if body[5] != self._body_quat:  # the body only slides: its rotation stays
            self._body_quat = body[5]
            self._top_offset = (_rot(body[5]) @ self._loc_top).tolist()
        (x, y, z), o = body[4], self._top_offset
        top = [x + o[0], y + o[1], z + o[2]]
        self._arm_offsets = w = np.matmul(R_arm, self._arm_locals).reshape(-1, 3).tolist()
        x, y, z = arm[4]
        bot = [x + w[0][0], y + w[0][1], z + w[0][2]]
        self._pad = [x + w[1][0], y + w[1][1], z + w[1][2]]
        d0, d1, d2 = top[0] - bot[0], top[1] - bot[1], top[2] - bot[2]
        self._damper_len = L = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        self._u = u = [d0 / L, d1 / L, d2 / L]  # unit vector arm mount -> body mount
        v_top = point_velocity(body, top)
        v_bot = point_velocity(arm, bot)
        self._v_damper = -(0.0 + u[0] * (v_top[0] - v_bot[0]) + u[1] * (v_top[1] - v_bot[1])
                           + u[2] * (v_top[2] - v_bot[2]))  # compression rate (numpy's dot)
        self._top, self._bot = top, bot

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
        p.applyExternalForce(b, HUB, [0, 0, self._F_t], self._hub_pos, p.WORLD_FRAME,
                             physicsClientId=c)
        F_d, u = self._F_d, self._u
        f = [F_d * u[0], F_d * u[1], F_d * u[2]]
        p.applyExternalForce(b, BODY, f, self._top, p.WORLD_FRAME, physicsClientId=c)
        p.applyExternalForce(b, LOWER_ARM, [-f[0], -f[1], -f[2]], self._bot, p.WORLD_FRAME,
                             physicsClientId=c)
        if self._F_bs > 0.0:  # bumper: up on the body, down on the arm's pad, at the pad
            pad = self._pad
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
        return {"z_b": np.array([self._zb_abs - self._z_b0]), "v_b": np.array([self._vb]),
                "z_w": np.array([self._zw_abs - self._z_w0]), "v_w": np.array([self._vw]),
                "z_damper": np.array([self._L0 - self._damper_len]),
                "v_damper": np.array([self._v_damper]),
                "arm_angle": np.array([self._theta - self._theta0])}

    def spring_force(self) -> np.ndarray:
        """Dynamic torsion-bar torque expressed as a vertical force at the ball joint,
        K_theta (theta - theta_0) / L with L the corner's ball-joint lever
        (:func:`cosim.lower_arm.lever_ball_joint`, 0.294 m, for the built-in corner), upward
        on the body [N]."""
        return np.array([self._k_theta * (self._theta - self._theta0)
                         / self.geom.lever_ball_joint])

    def extra_response(self) -> dict[str, np.ndarray]:
        """``F_bs``: the jounce-bumper force [N] (>= 0) the next substep applies."""
        return {"F_bs": np.array([self.bump_stop_force()])}

    def response_velocities(self) -> dict[str, float]:
        """Vehicle-axes velocities [m/s] of the lower arm's points (module docstring), keyed
        by the fields the node derives from them, ``a_arm_{loc1,cg,loc2}_{x,y,z}`` (kinematic,
        no gravity): v_com + omega x (r - r_com) from the link state :meth:`_read` fetched."""
        arm = self._arm_state  # point_velocity's sums, inline (2 calls a step)
        (x, y, z), (v0, v1, v2), (w0, w1, w2), (c0, c1, c2) = arm[4], arm[6], arm[7], arm[0]
        out: dict[str, float] = {}
        for names, o in zip(self._accel_names, self._arm_offsets[2:], strict=True):
            r0, r1, r2 = x + o[0] - c0, y + o[1] - c1, z + o[2] - c2
            out[names[0]] = v0 + (w1 * r2 - w2 * r1)
            out[names[1]] = v1 + (w2 * r0 - w0 * r2)
            out[names[2]] = v2 + (w0 * r1 - w1 * r0)
        return out

    def substep(self, dt: float, F_t: np.ndarray, F_d: np.ndarray) -> None:
        if dt != self._dt:
            p.setTimeStep(dt, physicsClientId=self.client)
            self._dt = dt
        self._F_t, self._F_d = float(F_t[0]), float(F_d[0])
        self._tau = self.tau0 - self._k_theta * (self._theta - self._theta0)
        self._F_bs = self.bump_stop_force()
        # the pose the forces of this substep are applied (and the joint sensors evaluated) in
        self._applied_pose = (self._R_arm, self._hub_quat, self._u)
        self._ua_quat_applied = self._ua_quat
        self._apply()
        p.stepSimulation(physicsClientId=self.client)
        self._read()

    def loads_later(self) -> Callable[[], dict[str, dict[str, float]]]:
        """``arm``: the lower arm's loads (:func:`.arm_loads.arm_loads`); ``upper_arm``: the
        upper arm's (:func:`.upper_arm_loads.upper_arm_loads_later`)."""
        lower, upper = arm_loads_later(self), upper_arm_loads_later(self)
        return lambda: {"arm": lower(), "upper_arm": upper()}

    def info(self) -> dict[str, object]:
        d = super().info()
        bs = self.bump_stop
        d.update({"model": self.name, "corner_names": ["FL"], "wheel_x": [0.0],
                  "wheel_track": [0], "unsprung_mass": [self.params.unsprung_mass],
                  "torsion_preload_nm": self.tau0, "corner": self.corner.name,
                  "arm_points": {k: [float(x) for x in self.geom.to_arm_frame(v)]
                                 for k, v in self.geom.arm_points.items()},
                  "bump_stop": None if bs is None else {
                      "clearance_m": bs.clearance, "initial_rate_n_per_m": bs.initial_rate,
                      "stroke_m": bs.stroke}})
        return d


def _local(body: int, link: int, offset_from_link_origin: np.ndarray, client: int) -> list:
    """Constraint pivots are given relative to the link's centre of mass frame in PyBullet."""
    ls = p.getLinkState(body, link, physicsClientId=client)
    local_inertial_pos = np.array(ls[2])
    return (np.asarray(offset_from_link_origin) - local_inertial_pos).tolist()


def _link_point(origin: np.ndarray, corner_point: np.ndarray) -> np.ndarray:
    """A hardpoint (static corner frame) in the frame of a link at ``origin`` [m] (at rest
    the link frames have the corner's axes): [I | -origin] @ (point, 1)."""
    return np.hstack([np.eye(3), -origin[:, None]]) @ np.append(corner_point, 1.0)
