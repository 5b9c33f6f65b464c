"""Lumped 7-DOF full vehicle in PyBullet (thesis Ch. 4 Sec. 4.4, Fig. 4.2, Table 4.4).

Degrees of freedom: body heave z, pitch theta, roll phi (no yaw, no x/y translation) and the
four wheels' vertical motion (prismatic joints). Corners FL, FR, RL, RR are independent (no
anti-roll bar), each a spring k_s with F_d and F_t from the other nodes, as in the quarter car.

PyBullet: ground -prismatic z-> ``heave`` -revolute y-> ``pitch`` -revolute x-> ``body``
(mass M, I_yy pitch, I_xx roll at the CG); four ``wheel_i`` on prismatic z joints from the
ground. The intermediate links weigh 1 g, included in the static preload.

Axes ISO 8855 (x forward, y left, z up): pitch theta is a rotation about +y (positive
nose-down), roll phi about +x (positive left side up). Corner i at (x_i, y_i) from the CG moves
(exactly, for the chain above)

    z_bi = z - x_i sin(theta) + y_i sin(phi) cos(theta)     (~ z - x_i theta + y_i phi)

and the corner forces (spring + preload + damper, vertical, on the body) enter as generalised
forces through J_i = dz_bi/dq: Q_z = sum F_i, Q_theta = sum F_i dz_bi/dtheta, Q_phi = ...

Table 4.4: effective sprung mass front 535 kg, rear 400 kg, unsprung 47.8 kg, k_s 31 000 N/m,
c_s 1500 N s/m (controller node), k_t 239 000 N/m (tyre node), pitch inertia 1761.3 kg m^2,
roll inertia 465.3 kg m^2. The thesis gives no wheelbase or track; the defaults
L = 2.774 m, t = 1.411 m are those for which the tabulated inertias follow from the masses
read per axle (see shared/reference/thesis-ch4.md Sec. 4).

**One mass basis** (docs/vehicles_roads.md, "7-DOF full vehicle: choices"). Sec. 4.4 says the
sprung mass "is represented as lumped masses at each corner" (after Hudson [103]): the body is
point masses m_i at the corners (x_i, y_i), so M = sum m_i, the CG where the static corner
loads balance (a = L m_rear / (m_front + m_rear) behind the front axle) and, unless a scenario
gives them, I_pitch = sum m_i x_i^2, I_roll = sum m_i y_i^2 [kg m^2] (dynamic index
k_pitch^2 / (a b) exactly 1, Gillespie's "near unity"). ``mass_basis`` reads the masses per
**corner** (default: 1870 kg, a front corner the QVM's 535 kg: Appendix III's 1.14 Hz;
I = 3522.5 / 930.8 kg m^2, radii of gyration 1.372 m = 0.49 L and t/2 = 0.706 m, upper bounds
of App. I's 1600 kg MPV's 0.99 / 0.63 m) or per **axle** (935 kg, too light for an unladen
MPV; I = Table 4.4's printed 1761.3 / 465.3 kg m^2 to 0.1 %).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pybullet as p

from cosim.channels import CORNERS

from .model import GRAVITY, PlantModel
from .quarter_car_lumped import free_joints, load_urdf_text, new_direct_client

_EPS_MASS = 1e-3
_LINK = """ <link name="{name}"><inertial><origin xyz="0 0 0"/><mass value="{m}"/>
  <inertia ixx="{ixx}" iyy="{iyy}" izz="{izz}" ixy="0" ixz="0" iyz="0"/></inertial></link>
"""
_JOINT = """ <joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>
  <origin xyz="{x} {y} {z}"/><axis xyz="{axis}"/>
  <limit lower="-10" upper="10" effort="1e12" velocity="1e6"/></joint>
"""


@dataclass(frozen=True)
class FullVehicleParams:
    """Table 4.4 (unladen MPV) plus the assumed geometry."""

    sprung_mass_front: float = 535.0
    sprung_mass_rear: float = 400.0
    unsprung_mass: float = 47.8
    spring_stiffness: float = 31000.0
    pitch_inertia: float | None = None  # kg m^2; None: sum m_i x_i^2 of the corner masses
    roll_inertia: float | None = None   # kg m^2; None: sum m_i y_i^2 of the corner masses
    wheelbase: float = 2.774
    track: float = 1.411
    mass_basis: str = "corner"

    def __post_init__(self) -> None:
        """Fill the inertias from the lumped corner masses where the scenario gives none."""
        if self.mass_basis not in ("corner", "axle"):
            raise ValueError(f"mass_basis must be 'corner' or 'axle', got {self.mass_basis!r}")
        m, xy = self.corner_sprung_mass, self.corner_xy
        if self.pitch_inertia is None:
            object.__setattr__(self, "pitch_inertia", float(m @ xy[:, 0] ** 2))
        if self.roll_inertia is None:
            object.__setattr__(self, "roll_inertia", float(m @ xy[:, 1] ** 2))

    @property
    def I_pitch(self) -> float:
        """Body pitch inertia about the CG's y axis [kg m^2]."""
        return float(self.pitch_inertia)  # type: ignore[arg-type]  # set in __post_init__

    @property
    def I_roll(self) -> float:
        """Body roll inertia about the CG's x axis [kg m^2]."""
        return float(self.roll_inertia)  # type: ignore[arg-type]  # set in __post_init__

    @property
    def dynamic_index(self) -> float:
        """Pitch dynamic index DI = k_pitch^2 / (a b), k_pitch^2 = I_pitch / M [-]."""
        a = self.a
        return self.I_pitch / self.body_mass / (a * (self.wheelbase - a))

    @property
    def corner_sprung_mass(self) -> np.ndarray:
        """Static sprung load per corner / g [kg], order FL, FR, RL, RR."""
        f, r = self.sprung_mass_front, self.sprung_mass_rear
        if self.mass_basis == "axle":
            f, r = f / 2.0, r / 2.0
        return np.array([f, f, r, r])

    @property
    def body_mass(self) -> float:
        return float(self.corner_sprung_mass.sum())

    @property
    def a(self) -> float:
        """CG behind the front axle [m]."""
        m = self.corner_sprung_mass
        return self.wheelbase * (m[2] + m[3]) / m.sum()

    @property
    def corner_xy(self) -> np.ndarray:
        """Corner (x_i, y_i) from the CG [m], shape (4, 2)."""
        a, b, h = self.a, self.wheelbase - self.a, self.track / 2.0
        return np.array([[a, h], [a, -h], [-b, h], [-b, -h]])


def _urdf(pr: FullVehicleParams) -> str:
    e = _EPS_MASS
    links = _LINK.format(name="ground", m=0, ixx=0, iyy=0, izz=0)
    links += _LINK.format(name="heave", m=e, ixx=e, iyy=e, izz=e)
    links += _LINK.format(name="pitch", m=e, ixx=e, iyy=e, izz=e)
    links += _LINK.format(name="body", m=pr.body_mass, ixx=pr.I_roll,
                          iyy=pr.I_pitch, izz=pr.I_pitch + pr.I_roll)
    joints = _JOINT.format(name="heave", kind="prismatic", parent="ground", child="heave",
                           x=0, y=0, z=0, axis="0 0 1")
    joints += _JOINT.format(name="pitch", kind="revolute", parent="heave", child="pitch",
                            x=0, y=0, z=0, axis="0 1 0")
    joints += _JOINT.format(name="roll", kind="revolute", parent="pitch", child="body",
                            x=0, y=0, z=0, axis="1 0 0")
    for name, (x, y) in zip(CORNERS, pr.corner_xy, strict=True):
        links += _LINK.format(name=f"wheel_{name}", m=pr.unsprung_mass, ixx=1, iyy=1, izz=1)
        joints += _JOINT.format(name=f"z_w_{name}", kind="prismatic", parent="ground",
                                child=f"wheel_{name}", x=x, y=y, z=-0.3, axis="0 0 1")
    return f'<?xml version="1.0"?>\n<robot name="full_vehicle_7dof">\n{links}{joints}</robot>\n'


class FullVehicle7DOF(PlantModel):
    """7-DOF full vehicle; corners FL, FR, RL, RR."""

    n_corners = 4
    name = "full_vehicle_7dof"

    def __init__(self, params: FullVehicleParams | None = None) -> None:
        self.params = pr = params or FullVehicleParams()  # (mass_basis checked there)
        self.client = new_direct_client()
        self.body = load_urdf_text(_urdf(pr), self.client, useFixedBase=True,
                                   flags=p.URDF_USE_INERTIA_FROM_FILE)
        self._joints = list(range(7))  # heave, pitch, roll, wheels FL..RR
        free_joints(self.body, self._joints, self.client)
        self._xy = pr.corner_xy
        self._preload = pr.corner_sprung_mass * GRAVITY
        # weight of the 1 g intermediate links, carried by the heave joint at equilibrium
        self._extra_heave = 2 * _EPS_MASS * GRAVITY
        self._dt: float | None = None
        self._q = np.zeros(7)
        self._qd = np.zeros(7)

    # --- kinematics ---
    def _corner_kinematics(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Corner body displacement, velocity, and Jacobian rows dz_bi/d(z, theta, phi)."""
        z, th, ph = self._q[:3]
        zd, thd, phd = self._qd[:3]
        x, y = self._xy[:, 0], self._xy[:, 1]
        st, ct, sp, cp = np.sin(th), np.cos(th), np.sin(ph), np.cos(ph)
        zb = z - x * st + y * sp * ct
        J = np.stack([np.ones(4), -x * ct - y * sp * st, y * cp * ct], axis=1)
        vb = J @ np.array([zd, thd, phd])
        return zb, vb, J

    def static_tyre_load(self) -> np.ndarray:
        return self._preload + self.params.unsprung_mass * GRAVITY

    def state(self) -> dict[str, np.ndarray]:
        zb, vb, _ = self._corner_kinematics()
        return {"z_b": zb, "v_b": vb, "z_w": self._q[3:].copy(), "v_w": self._qd[3:].copy(),
                "heave": self._q[0:1].copy(), "pitch": self._q[1:2].copy(),
                "roll": self._q[2:3].copy(), "v_heave": self._qd[0:1].copy(),
                "w_pitch": self._qd[1:2].copy(), "w_roll": self._qd[2:3].copy()}

    def response_velocities(self) -> dict[str, np.ndarray]:
        """The body's pitch and roll rates [rad/s], which the node derives as ``alpha_pitch``
        and ``alpha_roll`` [rad/s^2] in ``plant/response`` (pitch +y nose down, roll +x left
        up), as it does a_b."""
        return {"alpha_pitch": self._qd[1:2].copy(), "alpha_roll": self._qd[2:3].copy()}

    def spring_force(self) -> np.ndarray:
        zb, _, _ = self._corner_kinematics()
        return self.params.spring_stiffness * (self._q[3:] - zb)

    def substep(self, dt: float, F_t: np.ndarray, F_d: np.ndarray) -> None:
        if dt != self._dt:
            p.setTimeStep(dt, physicsClientId=self.client)
            self._dt = dt
        _, _, J = self._corner_kinematics()
        F_s = self.spring_force()
        F_d = np.asarray(F_d, dtype=float)
        f_corner = F_s + self._preload + F_d          # on the body, upward
        Q_body = J.T @ f_corner
        Q_body[0] += self._extra_heave
        f_wheel = np.asarray(F_t, dtype=float) - f_corner
        forces = list(Q_body) + list(f_wheel)
        p.setJointMotorControlArray(self.body, self._joints, p.TORQUE_CONTROL, forces=forces,
                                    physicsClientId=self.client)
        p.stepSimulation(physicsClientId=self.client)
        js = p.getJointStates(self.body, self._joints, physicsClientId=self.client)
        self._q = np.array([s[0] for s in js])
        self._qd = np.array([s[1] for s in js])

    def info(self) -> dict[str, object]:
        pr = self.params
        d = super().info()
        d.update({"model": self.name, "corner_names": list(CORNERS),
                  "wheel_x": [0.0, 0.0, -pr.wheelbase, -pr.wheelbase],
                  "wheel_track": [0, 1, 0, 1], "wheelbase": pr.wheelbase, "track": pr.track,
                  "cg_to_front_axle": pr.a, "body_mass": pr.body_mass,
                  "pitch_inertia": pr.I_pitch, "roll_inertia": pr.I_roll,
                  "dynamic_index": pr.dynamic_index, "unsprung_mass": [pr.unsprung_mass] * 4,
                  "spring_stiffness": [pr.spring_stiffness] * 4})
        return d
