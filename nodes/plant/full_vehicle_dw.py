"""Full vehicle on four double-wishbone corners built from corner files (docs/corners.md).

One PyBullet multibody: the **body** is the floating base (6 DOF, frame at the CG at ride
height); each corner FL, FR, RL, RR is the quarter car's linkage (:class:`.double_wishbone_
geometry.CornerGeometry`; the loops closed by POINT2POINT constraints), the front ones from
the ``front`` corner file, the rear from ``rear`` (FR, RR mirrored: :meth:`cosim.corner.
Corner.mirrored`), static wheel centres at (x_i, +-half track, r - h_cg) from the CG, x = a
ahead for the front axle, b = L - a behind for the rear.

Forces per corner, as :mod:`.double_wishbone` applies them: the torsion bar tau = tau_0 -
K_theta theta (plus the axle's :mod:`.anti_roll_bar` torque) on the lower arm's joint, F_d
along the damper axis, the bumper along the body's z, F_t vertical at the wheel centre; or,
once :meth:`~.full_vehicle_dw_wheels.WheelsAndDriver.set_tyre_forces` gave the Magic
Formula's F_x, F_y, M_z (:mod:`nodes.tyre_road.tyre_3d`), F_t along the road normal with
them at the contact point. The driver (:meth:`set_driver`) gives a torque on each wheel's
spin joint and the travel of the steering rack, a prismatic link carrying the front tie
rods' inner joints (a position motor; 2 kg, taken from the body at its CG).

**Static state.** The tyre loads W_i balance every link's weight and its pitch moment (left =
right), and the torsion preloads tau_0,i are those that leave the arms unaccelerated: the
arms' accelerations are affine in the four torques, so five trial steps from rest give them
(a 4 x 4 solve); the body is then at rest too.

Body (defaults: Table 4.4 read per corner, as ``full_vehicle_7dof``'s ``corner`` basis):
1870 kg, the CG a = 1.181 m behind the front axle (L = 2.774 m), I_pitch = 3522.5,
I_roll = 930.8 kg m^2 (sum m_i x_i^2, sum m_i y_i^2 of the corner masses), I_yaw their sum;
CG height h_cg = 0.55 m (ours: a small MPV's unladen CG, the thesis gives none).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from cosim import corner as corner_file
from cosim.channels import CORNERS
from cosim.corner import Corner

from .anti_roll_bar import ARB_FRONT_NM_PER_DEG, ARB_REAR_NM_PER_DEG, axle_bars, axle_torques
from .arm_loads import arm_loads_at
from .bump_stop import BumpStopParams, bump_stop_force
from .double_wishbone_geometry import CornerGeometry, _joint, _link
from .driver import Driver
from .full_vehicle_dw_wheels import WheelsAndDriver, steer_lever, wheel_inertia, wheel_mass
from .model import GRAVITY, PlantModel
from .quarter_car_lumped import load_urdf_text, new_direct_client, release_joint
from .quarter_car_lumped import quat_matrix as _rot
from .quiet_pybullet import p


@dataclass(frozen=True)
class FullVehicleDWParams:
    """The body of the four-corner vehicle (module docstring) [kg, kg m^2, m]."""

    sprung_mass: float = 1870.0
    cg_to_front_axle: float = 2.774 * 800.0 / 1870.0
    """a [m]: the 7-DOF's, from 535 / 400 kg per front / rear corner."""
    wheelbase: float = 2.774
    pitch_inertia: float = 3522.5
    roll_inertia: float = 930.8
    yaw_inertia: float = 3522.5 + 930.8
    cg_height: float = 0.55
    anti_roll_bars: bool = True
    """A bar on each axle (:mod:`.anti_roll_bar`); false: none."""
    arb_front_nm_per_deg: float = ARB_FRONT_NM_PER_DEG
    """The front bar's roll stiffness at the wheels [N m/deg] (the value's reasoning there)."""
    arb_rear_nm_per_deg: float = ARB_REAR_NM_PER_DEG
    """The rear bar's [N m/deg]."""
    speed_kmh: float = 0.0
    """The forward speed at t = 0 [km/h]: body and wheel centres at it, the wheels spinning
    at v / r_l (free rolling on the tyre of :mod:`nodes.tyre_road.tyre_3d`)."""


_ST = ("theta", "hub", "vhub", "top", "bot", "vtop", "vbot", "pad", "R_arm", "hub_q", "wc",
       "vwc", "axis", "spin", "L_d", "u")
"""What :meth:`FullVehicleDoubleWishbone._read` keeps per corner (world axes, SI units)."""

RACK_MASS = 2.0
"""The steering rack's mass [kg], taken from ``sprung_mass`` (the rack is body) and placed at
the CG, so the vehicle's mass and CG do not move (ours: a small car's rack and pinion)."""


class FullVehicleDoubleWishbone(WheelsAndDriver, PlantModel):
    """Four double-wishbone corners on a free body; corners FL, FR, RL, RR."""

    n_corners = 4
    name = "full_vehicle_double_wishbone"

    def __init__(self, params: FullVehicleDWParams | None = None, front: Corner | None = None,
                 rear: Corner | None = None, static_dt: float = 1e-3,
                 driver: Mapping[str, Any] | None = None) -> None:
        self.params = pr = params or FullVehicleDWParams()
        f = front or corner_file.builtin()
        r = rear or f
        for c in (f, r):
            if c.coil_n_per_m > 0.0:
                raise ValueError(f"{c.source}: the PyBullet corner has no coil spring yet")
        self.corners = [f, f.mirrored(), r, r.mirrored()]
        self.geoms = [CornerGeometry(c) for c in self.corners]
        self.side = np.array([1.0, -1.0, 1.0, -1.0])  # +1 left: arm angle + = jounce
        a, b = pr.cg_to_front_axle, pr.wheelbase - pr.cg_to_front_axle
        self.wheel_centres = np.array([
            [x, s * c.half_track, c.tyre_loaded_radius - pr.cg_height]
            for x, s, c in zip((a, a, -b, -b), self.side, self.corners, strict=True)])
        self.k_theta = np.array([c.torsion_bar_nm_per_deg * 180.0 / np.pi
                                 for c in self.corners])
        self.bars = axle_bars(f, r, pr.anti_roll_bars, pr.arb_front_nm_per_deg,
                              pr.arb_rear_nm_per_deg)
        self.bump = [None if c.bump_stop is None else BumpStopParams(**c.bump_stop)
                     for c in self.corners]
        self.client = cl = new_direct_client()
        p.setPhysicsEngineParameter(numSolverIterations=200, erp=0.2,
                                    solverResidualThreshold=1e-12, physicsClientId=cl)
        self.body = bd = load_urdf_text(self._urdf(), cl, useFixedBase=False,
                                        basePosition=[0.0, 0.0, pr.cg_height],
                                        flags=p.URDF_USE_INERTIA_FROM_FILE)
        names = {p.getJointInfo(bd, j, physicsClientId=cl)[1].decode(): j
                 for j in range(p.getNumJoints(bd, physicsClientId=cl))}
        self.link = [{k: names[f"{k}_{n}"] for k in ("lower_arm", "hub", "upper_arm",
                                                     "tie_rod", "wheel")} for n in CORNERS]
        self.rack = names["rack"]
        for j in names.values():
            release_joint(bd, j, cl)
        for j in [-1, *names.values()]:
            p.changeDynamics(bd, j, linearDamping=0, angularDamping=0, jointDamping=0,
                             physicsClientId=cl)
        for i, g in enumerate(self.geoms):
            wc, lk = self.wheel_centres[i], self.link[i]
            for parent, child, pt in (("upper_arm", "hub", g.upper_ball_joint),
                                      ("tie_rod", "hub", g.tie_rod_outer)):
                cid = p.createConstraint(bd, lk[parent], bd, lk[child], p.JOINT_POINT2POINT,
                                         [0, 0, 0], self._local(lk[parent], wc + pt),
                                         self._local(lk[child], wc + pt), physicsClientId=cl)
                p.changeConstraint(cid, maxForce=1e9, physicsClientId=cl)
        self._arm_r_com = [p.getLinkState(bd, lk["lower_arm"], physicsClientId=cl)[2]
                           for lk in self.link]
        self._pad_body = [None if g.bump_stop_pad is None else self.wheel_centres[i]
                          + g.bump_stop_pad for i, g in enumerate(self.geoms)]
        # per corner: the damper's top (body frame), its seat and the pad (arm link frame)
        self._damper_pad = []
        for wc, g, pad in zip(self.wheel_centres, self.geoms, self._pad_body, strict=True):
            la_o = wc + 0.5 * (g.lower_bush_front + g.lower_bush_rear)
            self._damper_pad.append((wc + g.damper_upper, wc + g.damper_lower - la_o,
                                     None if pad is None else pad - la_o))
        self._F_t = np.zeros(4)
        self._F_d = np.zeros(4)
        self._tau = np.zeros(4)
        self.r_l = np.array([c.tyre_loaded_radius for c in self.corners])
        self.steer_lever = float(np.mean([steer_lever(g) for g in self.geoms[:2]]))
        self._F_road: np.ndarray | None = None  # (4, 3): Fx, Fy, Mz in the road plane
        self._T_wheel = np.zeros(4)
        self._rack = 0.0
        self._dt: float | None = None
        self._read()
        self._s0 = self._snapshot()
        self.tau0 = np.zeros(4)
        self._W = self._static_loads()
        self.tau0 = self._static_torques(static_dt)
        if pr.speed_kmh > 0.0:
            self._launch(pr.speed_kmh / 3.6)
        self._read()
        self._time = 0.0
        self.driver = None if driver is None else Driver(
            mass=float(self._W.sum()) / GRAVITY, wheel_radius=float(self.r_l[0]),
            wheelbase=pr.wheelbase, **driver)
        """The driver the model runs itself each substep (a run over the bus: the scenario's
        ``vehicle.driver``; :mod:`.driver`), or None (inputs by :meth:`set_driver`)."""

    # --- build ---
    def _urdf(self) -> str:
        pr = self.params
        s = _link("body", pr.sprung_mass - RACK_MASS, [0, 0, 0],
                  (pr.roll_inertia, pr.pitch_inertia, pr.yaw_inertia))
        s += _link("rack", RACK_MASS, [0, 0, 0], (0.01, 0.01, 0.01))
        joints = _joint("rack", "prismatic", "body", "rack", [0, 0, 0], "0 1 0")
        for i, (g, c, n) in enumerate(zip(self.geoms, self.corners, CORNERS, strict=True)):
            wc, m, m_w = self.wheel_centres[i], c.masses, wheel_mass(c)
            lower, others, js = g.arm_urdf((m["lower_arm"], m["upper_arm"], m["tie_rod"]),
                                           f"_{n}", wc, "rack" if i < 2 else "body")
            bj = wc + g.lower_ball_joint
            s += (lower + _link(f"hub_{n}", m["hub"] - m_w, wc - bj, (0.15, 0.15, 0.15))
                  + _link(f"wheel_{n}", m_w, [0, 0, 0], wheel_inertia(m_w)) + others)
            joints += js + _joint(f"wheel_{n}", "continuous", f"hub_{n}", f"wheel_{n}", wc - bj,
                                  "0 1 0")
        return f'<?xml version="1.0"?>\n<robot name="full_vehicle_dw">\n{s}{joints}</robot>\n'

    def _local(self, link: int, body_point: np.ndarray) -> list[float]:
        """A point given in the body frame at build time, in ``link``'s centre-of-mass
        frame (the link frames are parallel to the body's then)."""
        ls = p.getLinkState(self.body, link, computeForwardKinematics=1,
                            physicsClientId=self.client)
        base, _ = p.getBasePositionAndOrientation(self.body, physicsClientId=self.client)
        return (np.asarray(body_point) + np.asarray(base) - np.asarray(ls[0])).tolist()

    def _static_loads(self) -> np.ndarray:
        """W_i [N]: the force and pitch-moment balance of every link's weight, left = right."""
        cl, bd = self.client, self.body
        base, _ = p.getBasePositionAndOrientation(bd, physicsClientId=cl)
        masses = [p.getDynamicsInfo(bd, -1, physicsClientId=cl)[0],
                  p.getDynamicsInfo(bd, self.rack, physicsClientId=cl)[0]]
        xs = [0.0, 0.0]
        for lk in self.link:
            for j in lk.values():
                masses.append(p.getDynamicsInfo(bd, j, physicsClientId=cl)[0])
                xs.append(p.getLinkState(bd, j, physicsClientId=cl)[0][0] - base[0])
        W = float(np.sum(masses)) * GRAVITY
        M_y = float(np.dot(masses, xs)) * GRAVITY  # sum m g x
        xf, xr = self.wheel_centres[0, 0], self.wheel_centres[2, 0]
        # W_f + W_r = W, W_f xf + W_r xr = M_y (each axle's load shared left = right)
        W_f = (M_y - W * xr) / (xf - xr)
        return np.array([W_f, W_f, W - W_f, W - W_f]) / 2.0

    def _static_torques(self, dt: float) -> np.ndarray:
        cl, bd = self.client, self.body
        p.setTimeStep(dt, physicsClientId=cl)
        sid = p.saveState(physicsClientId=cl)
        trials = [np.zeros(4)] + [np.eye(4)[i] * 1000.0 for i in range(4)]
        om = []
        for tau in trials:
            p.restoreState(sid, physicsClientId=cl)
            self._read()
            self._F_t, self._F_d, self._tau = self._W.copy(), np.zeros(4), tau
            self._apply()
            p.stepSimulation(physicsClientId=cl)
            om.append([p.getJointState(bd, lk["lower_arm"], physicsClientId=cl)[1]
                       for lk in self.link])
        p.restoreState(sid, physicsClientId=cl)
        p.removeState(sid, physicsClientId=cl)
        self._dt = dt
        om0 = np.array(om[0])
        A = np.column_stack([(np.array(om[i + 1]) - om0) / 1000.0 for i in range(4)])
        return np.linalg.solve(A, -om0)

    # --- state ---
    def _read(self) -> None:
        cl, bd = self.client, self.body
        pos, quat = p.getBasePositionAndOrientation(bd, physicsClientId=cl)
        v, w = p.getBaseVelocity(bd, physicsClientId=cl)
        self._base = P, R, V, Wb, _ = (np.array(pos), _rot(quat), np.array(v), np.array(w),
                                       quat)
        st: dict[str, list] = {k: [] for k in _ST}
        for lk, (top_b, bot_a, pad_a) in zip(self.link, self._damper_pad, strict=True):
            theta = p.getJointState(bd, lk["lower_arm"], physicsClientId=cl)[0]
            hub, arm, wh = (p.getLinkState(bd, lk[k], computeLinkVelocity=1,
                                           computeForwardKinematics=1, physicsClientId=cl)
                            for k in ("hub", "lower_arm", "wheel"))
            Ra = _rot(arm[5])
            bot = np.array(arm[4]) + Ra @ bot_a
            top = P + R @ top_b
            d = top - bot
            L = np.linalg.norm(d)
            ax = _rot(wh[5])[:, 1]
            for k, x in zip(_ST, (
                    theta, np.array(hub[0]), np.array(hub[6]), top, bot,
                    V + np.cross(Wb, top - P),
                    np.array(arm[6]) + np.cross(arm[7], bot - np.array(arm[0])),
                    None if pad_a is None else np.array(arm[4]) + Ra @ pad_a, Ra, hub[5],
                    np.array(wh[0]), np.array(wh[6]), ax, float(np.dot(wh[7], ax)), L, d / L),
                    strict=True):
                st[k].append(x)
        self._st = st

    def _snapshot(self) -> dict[str, np.ndarray]:
        """Positions at build time (static): wheel centres, damper lengths, pads, body."""
        st = self._st
        return {"hub_z": np.array([h[2] for h in st["hub"]]),
                "L_d": np.array(st["L_d"]),
                "theta": np.array(st["theta"]), "base": self._base[0].copy(),
                "pad_z": np.array([np.nan if q is None else q[2] for q in st["pad"]]),
                "bumper_z": np.array([np.nan if q is None else
                                      (self._base[0] + self._base[1] @ q)[2]
                                      for q in self._pad_body])}

    def _corner_body_points(self) -> tuple[np.ndarray, np.ndarray]:
        """World z and vertical velocity of the body points at the static wheel centres."""
        P, R, V, Wb = self._base[:4]
        pts = P + np.matmul(R, self.wheel_centres[:, :, None])[:, :, 0]  # each R @ wc's bits
        return pts[:, 2], (V + np.cross(Wb, pts - P))[:, 2]

    def _bump_forces(self) -> np.ndarray:
        F = np.zeros(4)
        s0 = self._s0
        for i, bs in enumerate(self.bump):
            pad = self._st["pad"][i]
            if bs is None or pad is None:
                continue
            bumper_z = (self._base[0] + self._base[1] @ self._pad_body[i])[2]
            d = (pad[2] - s0["pad_z"][i]) - (bumper_z - s0["bumper_z"][i]) - bs.clearance
            F[i] = bump_stop_force(d, bs)
        return F

    def _apply(self) -> None:
        cl, bd = self.client, self.body
        p.setJointMotorControl2(bd, self.rack, p.POSITION_CONTROL, targetPosition=self._rack,
                                targetVelocity=0.0, positionGain=1.0, velocityGain=1.0,
                                force=1e7, physicsClientId=cl)
        bump = self._bump_forces() if hasattr(self, "_s0") else np.zeros(4)
        ez = self._base[1][:, 2]
        st = self._st
        # the pose and forces of this substep, for the arm loads (:meth:`corner_arm_loads`)
        self._applied = [(st["R_arm"][i], st["hub_q"][i], st["u"][i], float(self._F_d[i]),
                          -bump[i] * ez) for i in range(4)]
        for i, lk in enumerate(self.link):
            p.setJointMotorControl2(bd, lk["lower_arm"], p.TORQUE_CONTROL,
                                    force=float(self._tau[i]), physicsClientId=cl)
            if self._F_road is None:
                p.applyExternalForce(bd, lk["hub"], [0.0, 0.0, float(self._F_t[i])],
                                     self._st["hub"][i].tolist(), p.WORLD_FRAME,
                                     physicsClientId=cl)
            else:
                P, e = self.contact_frame(i)
                Fx, Fy, Mz = self._F_road[i]
                F = Fx * e[0] + Fy * e[1] + float(self._F_t[i]) * e[2]
                p.applyExternalForce(bd, lk["wheel"], F.tolist(), P.tolist(), p.WORLD_FRAME,
                                     physicsClientId=cl)
                p.applyExternalTorque(bd, lk["wheel"], (Mz * e[2]).tolist(), p.WORLD_FRAME,
                                      physicsClientId=cl)
            p.setJointMotorControl2(bd, lk["wheel"], p.TORQUE_CONTROL,
                                    force=float(self._T_wheel[i]), physicsClientId=cl)
            top, bot = self._st["top"][i], self._st["bot"][i]
            f = self._F_d[i] * st["u"][i]
            p.applyExternalForce(bd, -1, f.tolist(), top.tolist(), p.WORLD_FRAME,
                                 physicsClientId=cl)
            p.applyExternalForce(bd, lk["lower_arm"], (-f).tolist(), bot.tolist(),
                                 p.WORLD_FRAME, physicsClientId=cl)
            if bump[i] > 0.0:
                pad = self._st["pad"][i]
                p.applyExternalForce(bd, -1, (bump[i] * ez).tolist(), pad.tolist(),
                                     p.WORLD_FRAME, physicsClientId=cl)
                p.applyExternalForce(bd, lk["lower_arm"], (-bump[i] * ez).tolist(),
                                     pad.tolist(), p.WORLD_FRAME, physicsClientId=cl)

    # --- PlantModel ---
    def static_tyre_load(self) -> np.ndarray:
        return self._W.copy()

    def state(self) -> dict[str, np.ndarray]:
        st, s0 = self._st, self._s0
        zb, vb = self._corner_body_points()
        v_d = np.array([-float(ui @ (vt - vbt)) for ui, vt, vbt in
                        zip(st["u"], st["vtop"], st["vbot"], strict=True)])
        R = self._base[1]
        roll, pitch = float(np.arctan2(R[2, 1], R[2, 2])), float(np.arcsin(-R[2, 0]))
        w_body = R.T @ self._base[3]
        zc = self._s0["base"][2]
        return {**self.wheel_kinematics(), **self.body_motion(),
                "z_b": zb - (zc + self.wheel_centres[:, 2]), "v_b": vb,
                "z_w": np.array([h[2] for h in st["hub"]]) - s0["hub_z"],
                "v_w": np.array([v[2] for v in st["vhub"]]),
                "z_damper": s0["L_d"] - np.array(st["L_d"]), "v_damper": v_d,
                "arm_angle": self.side * (np.array(st["theta"]) - s0["theta"]),
                "heave": np.array([self._base[0][2] - zc]), "pitch": np.array([pitch]),
                "roll": np.array([roll]), "v_heave": np.array([self._base[2][2]]),
                "w_pitch": np.array([w_body[1]]), "w_roll": np.array([w_body[0]])}

    def spring_force(self) -> np.ndarray:
        """Torsion-bar torque's dynamic part as a vertical force at each ball joint [N]."""
        dth = np.array(self._st["theta"]) - self._s0["theta"]
        lever = np.array([g.lever_ball_joint for g in self.geoms])
        return self.side * self.k_theta * dth / lever

    def extra_response(self) -> dict[str, np.ndarray]:
        return {"F_bs": self._bump_forces()}

    def substep(self, dt: float, F_t: np.ndarray, F_d: np.ndarray) -> None:
        if dt != self._dt:
            p.setTimeStep(dt, physicsClientId=self.client)
            self._dt = dt
        self._F_t = np.asarray(F_t, dtype=float).copy()
        self._F_d = np.asarray(F_d, dtype=float).copy()
        if self.driver is not None:
            mo = self.body_motion()
            torques, delta = self.driver.command(self._time, float(mo["u"][0]),
                                                 float(mo["w_yaw"][0]), dt)
            self.set_driver(torques, self.rack_for_steer(delta))
        self._time += dt
        dth = np.array(self._st["theta"]) - self._s0["theta"]
        self._tau = self.tau0 - self.k_theta * dth + self.side * axle_torques(self.bars,
                                                                              self.side * dth)
        self._apply()
        p.stepSimulation(physicsClientId=self.client)
        self._read()

    def corner_arm_loads(self) -> dict[str, dict[str, float]]:
        """The loads ON each corner's lower arm during the latest substep, by corner name,
        the ``arm`` channel's fields (:func:`.arm_loads.arm_loads_at`) [N, N m]. The left
        arms' in their arm frame (x forward along the pivot axis, y outboard, z up); the
        right arms' in the **mirrored** frame (x forward, y outboard, z up: left-handed in
        vehicle axes), where a force's components and a moment's (M_x: the torsion bar's
        and the anti-roll bar's, sign flipped: a moment is a pseudovector) are those of the
        left part under the mirrored load: the left part's FE unit cases give its stresses."""
        return self._corner_arm_loads_later()()

    def _corner_arm_loads_later(self) -> Callable[[], dict[str, dict[str, float]]]:
        """:meth:`corner_arm_loads` with the joint sensors read now, the rest at the call."""
        args = []
        for i, (g, lk) in enumerate(zip(self.geoms, self.link, strict=True)):
            R_arm, hub_q, u, F_d, bump = self._applied[i]
            args.append((
                p.getJointState(self.body, lk["lower_arm"], physicsClientId=self.client)[2],
                p.getJointStateMultiDof(self.body, lk["hub"], physicsClientId=self.client)[2],
                g.arm_rotation, (R_arm, hub_q, u), self._arm_r_com[i], F_d, bump,
                g.bush_spacing))

        def loads() -> dict[str, dict[str, float]]:
            out: dict[str, dict[str, float]] = {}
            for a, side, name in zip(args, self.side, CORNERS, strict=True):
                one = arm_loads_at(*a)
                if side < 0:  # proper frame (x, y out, z down) -> mirrored (z up)
                    one = {k: (-v if k.endswith("_z") or k == "torsion_bar_mx" else v)
                           for k, v in one.items()}
                out[name] = one
            return out

        return loads

    def loads_later(self) -> Callable[[], dict[str, dict[str, float]]]:
        """Every corner's lower-arm loads on its channel ``arm_FL`` .. ``arm_RR``
        (:meth:`corner_arm_loads`), and ``arm`` = the front-left's (docs/corners.md)."""
        corner = self._corner_arm_loads_later()

        def loads() -> dict[str, dict[str, float]]:
            al = corner()
            return {"arm": al["FL"], **{f"arm_{c}": al[c] for c in CORNERS}}

        return loads

    def info(self) -> dict[str, object]:
        d = super().info()
        pr = self.params
        d.update({"model": self.name, "corner_names": list(CORNERS),
                  "corners": [c.name for c in self.corners],
                  "wheel_x": [0.0, 0.0, -pr.wheelbase, -pr.wheelbase],
                  "wheel_track": [0, 1, 0, 1], "wheelbase": pr.wheelbase,
                  "cg_to_front_axle": pr.cg_to_front_axle, "body_mass": pr.sprung_mass,
                  "unsprung_mass": [sum(c.masses[k] for k in
                                        ("hub", "lower_arm", "upper_arm", "tie_rod"))
                                    for c in self.corners],
                  "torsion_preload_nm": [float(x) for x in self.tau0],
                  "anti_roll_bar_nm_per_rad": [0.0 if b is None else b.roll_stiffness
                                               for b in self.bars]})
        return d
