"""Lumped 2-DOF quarter car in PyBullet (thesis Ch. 3, Eq. 3.1, Table 3.1).

Two rigid bodies on vertical prismatic joints from a fixed ground: the sprung mass M_b (body)
and the unsprung mass M_w (wheel). The suspension spring k_s acts between them (computed here
and applied as joint forces, with its static preload so the model starts in equilibrium);
the damper force F_d and the tyre force F_t come from other nodes and are applied as actuator
forces, as the thesis applies them to its vN4D model as linear force actuators.

Joint positions are displacements from static equilibrium: z_b, z_w [m].
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass

import numpy as np

from .model import GRAVITY, PlantModel
from .quiet_pybullet import p

_URDF = """<?xml version="1.0"?>
<robot name="quarter_car_lumped">
 <link name="ground"><inertial><mass value="0"/>
  <inertia ixx="0" iyy="0" izz="0" ixy="0" ixz="0" iyz="0"/></inertial></link>
 <link name="body"><inertial><mass value="{mb}"/>
  <inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
 <link name="wheel"><inertial><mass value="{mw}"/>
  <inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
 <joint name="z_b" type="prismatic"><parent link="ground"/><child link="body"/>
  <axis xyz="0 0 1"/><limit lower="-10" upper="10" effort="1e12" velocity="1e6"/></joint>
 <joint name="z_w" type="prismatic"><parent link="ground"/><child link="wheel"/>
  <axis xyz="0 0 1"/><limit lower="-10" upper="10" effort="1e12" velocity="1e6"/></joint>
</robot>
"""


@dataclass(frozen=True)
class LumpedQuarterCarParams:
    """Table 3.1 (Ford Granada, Crolla et al.).

    sprung_mass M_b [kg], unsprung_mass M_w [kg], spring_stiffness k_s [N/m].
    The damper c_s and tyre k_t live in the controller and tyre/road nodes.
    """

    sprung_mass: float = 317.5
    unsprung_mass: float = 45.4
    spring_stiffness: float = 22000.0


def new_direct_client() -> int:
    """A fresh PyBullet physics client in DIRECT mode (no GUI), gravity on."""
    client = p.connect(p.DIRECT)
    p.setGravity(0, 0, -GRAVITY, physicsClientId=client)
    return client


def quat_matrix(quat) -> np.ndarray:
    """The 3x3 rotation matrix of a PyBullet quaternion."""
    return np.array(p.getMatrixFromQuaternion(quat)).reshape(3, 3)


def release_joint(body: int, j: int, client: int) -> None:
    """Switch off joint ``j``'s default motor (spherical or not) and enable its force sensor."""
    if p.getJointInfo(body, j, physicsClientId=client)[2] == p.JOINT_SPHERICAL:
        p.setJointMotorControlMultiDof(body, j, p.POSITION_CONTROL, [0, 0, 0, 1],
                                       targetVelocity=[0, 0, 0], positionGain=0, velocityGain=0,
                                       force=[0, 0, 0], physicsClientId=client)
    else:
        p.setJointMotorControl2(body, j, p.VELOCITY_CONTROL, force=0, physicsClientId=client)
    p.enableJointForceTorqueSensor(body, j, True, physicsClientId=client)


def free_joints(body: int, joints: list[int], client: int) -> None:
    """Remove PyBullet's default joint motors and damping so only our forces act."""
    for j in joints:
        p.setJointMotorControl2(body, j, p.VELOCITY_CONTROL, force=0, physicsClientId=client)
        p.changeDynamics(body, j, linearDamping=0, angularDamping=0, jointDamping=0,
                         physicsClientId=client)
    p.changeDynamics(body, -1, linearDamping=0, angularDamping=0, physicsClientId=client)


def load_urdf_text(text: str, client: int, **kwargs) -> int:
    """Load a URDF given as a string (PyBullet needs a file)."""
    fd, path = tempfile.mkstemp(suffix=".urdf", prefix="suscosim_")
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
        return p.loadURDF(path, physicsClientId=client, **kwargs)
    finally:
        os.unlink(path)


class LumpedQuarterCar(PlantModel):
    """2-DOF quarter car, Eq. 3.1: M_b z''_b = k_s (z_w - z_b) + F_d, and the wheel likewise."""

    n_corners = 1
    name = "quarter_car_lumped"

    def __init__(self, params: LumpedQuarterCarParams | None = None) -> None:
        self.params = params or LumpedQuarterCarParams()
        pr = self.params
        self.client = new_direct_client()
        self.body = load_urdf_text(_URDF.format(mb=pr.sprung_mass, mw=pr.unsprung_mass),
                                   self.client, useFixedBase=True,
                                   flags=p.URDF_USE_INERTIA_FROM_FILE)
        self._joints = [0, 1]
        free_joints(self.body, self._joints, self.client)
        self._dt: float | None = None
        self._z_b = self._z_w = self._v_b = self._v_w = 0.0  # [m], [m/s] (plain floats:
        # numpy's per-call cost dominates on two numbers, and this runs 4x per step)

    def static_tyre_load(self) -> np.ndarray:
        pr = self.params
        return np.array([(pr.sprung_mass + pr.unsprung_mass) * GRAVITY])

    def _read(self) -> None:
        (self._z_b, self._v_b, *_), (self._z_w, self._v_w, *_) = p.getJointStates(
            self.body, self._joints, physicsClientId=self.client)

    def state(self) -> dict[str, np.ndarray]:
        return {"z_b": np.array((self._z_b,)), "v_b": np.array((self._v_b,)),
                "z_w": np.array((self._z_w,)), "v_w": np.array((self._v_w,))}

    def _spring(self) -> float:
        """F_s = k_s (z_w - z_b) [N], on the body, upward positive (dynamic part)."""
        return self.params.spring_stiffness * (self._z_w - self._z_b)

    def spring_force(self) -> np.ndarray:
        return np.array((self._spring(),))

    def substep(self, dt: float, F_t: np.ndarray, F_d: np.ndarray) -> None:
        if dt != self._dt:
            p.setTimeStep(dt, physicsClientId=self.client)
            self._dt = dt
        pr = self.params
        F_s = self._spring()
        f_d = float(F_d[0])
        preload = pr.sprung_mass * GRAVITY  # static spring force holding the body up
        f_body = F_s + preload + f_d
        f_wheel = float(F_t[0]) - F_s - preload - f_d
        # F_t is absolute (it includes the static load that holds the wheel up); gravity acts
        # on both bodies through PyBullet.
        p.setJointMotorControlArray(self.body, self._joints, p.TORQUE_CONTROL,
                                    forces=[f_body, f_wheel], physicsClientId=self.client)
        p.stepSimulation(physicsClientId=self.client)
        self._read()

    def info(self) -> dict[str, object]:
        """Adds the wheel-path geometry: one corner, named FR, on the right track (the thesis
        runs its realistic QVM on the right-hand path), at the front axle (wheel_x = 0)."""
        pr = self.params
        d = super().info()
        d.update({
            "model": self.name, "corner_names": ["FR"], "wheel_x": [0.0], "wheel_track": [1],
            "sprung_mass": pr.sprung_mass, "unsprung_mass": [pr.unsprung_mass],
            "spring_stiffness": [pr.spring_stiffness],
        })
        return d
