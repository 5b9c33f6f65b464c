"""The four-corner vehicle, its 3-D tyres, a passive damper and the driver stepped together in
one process, in the co-simulation's exchange: every communication step h the
tyre forces, damper forces and driver's inputs are computed from the plant's state at t_k and
held over the step's substeps, as the distributed run's sequential exchange with the ``hold``
coupling does. Pure numerics (no bus, no files): the bars' tests and studies use it; a run
over the bus uses the same model objects in the plant and tyre/road nodes.

The road: flat (z_g = 0) unless ``road`` is given, a callable (x [m], track 0 left / 1 right)
-> z_g [m] at the wheel centre's world x (the body really moves: the contact's place on the
road is where the wheel is, not v t).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from cosim.channels import CORNERS
from nodes.tyre_road.tyre_3d import Tyre3D

from .driver import Driver
from .full_vehicle_dw import FullVehicleDoubleWishbone


@dataclass
class Histories:
    """Time histories of a run: per-step arrays (n,) or (n, 4) (FL, FR, RL, RR)."""

    t: np.ndarray
    F_z: np.ndarray
    F_x: np.ndarray
    F_y: np.ndarray
    u: np.ndarray
    w_yaw: np.ndarray
    a_x: np.ndarray
    """The CG's forward acceleration [m/s^2] (du/dt - v r, body axes), per step."""
    a_y: np.ndarray
    """Lateral acceleration [m/s^2] (dv/dt + u r)."""
    pitch: np.ndarray
    roll: np.ndarray
    delta: np.ndarray
    arm: dict[str, dict[str, np.ndarray]]
    """The lower arms' loads by corner and field (the ``plant/arm`` fields)."""


def simulate(car: FullVehicleDoubleWishbone, tyre: Tyre3D, driver: Driver, t_end: float,
             h: float, substeps: int, k_t: float, c_damper: float,
             road: Callable[[float, int], float] | None = None) -> Histories:
    """Step ``car`` to ``t_end`` [s] at communication step ``h`` [s] with ``substeps`` plant
    substeps: the point-contact F_z = max(0, W + k_t (z_g - z_w)) [N, N/m], the MF tyre's
    F_x, F_y, M_z, a linear damper F_d = ``c_damper`` v_damper [N s/m] along each damper and
    the driver's torques and steer. Returns the histories (arm loads of the step's first
    substep, as the plant node publishes them)."""
    W = car.static_tyre_load()
    n = int(round(t_end / h))
    dt = h / substeps
    rec: dict[str, list] = {k: [] for k in ("t", "F_z", "F_x", "F_y", "u", "v", "w_yaw",
                                            "pitch", "roll", "delta")}
    arm: dict[str, dict[str, list[float]]] = {c: {} for c in CORNERS}
    for k in range(n + 1):
        t = k * h
        st = car.state()
        z_g = np.zeros(4) if road is None else np.array(
            [road(float(x), i % 2) for i, x in enumerate(st["x_wc"])])
        F_z = np.maximum(0.0, W + k_t * (z_g - st["z_w"]))
        f = tyre.forces(st, F_z, h)
        torques, delta = driver.command(t, float(st["u"][0]), float(st["w_yaw"][0]), h)
        car.set_tyre_forces(f["Fx"], f["Fy"], f["Mz"])
        car.set_driver(torques, car.rack_for_steer(delta))
        F_d = c_damper * st["v_damper"]
        for name, val in (("t", t), ("F_z", F_z), ("F_x", f["Fx"]), ("F_y", f["Fy"]),
                          ("u", st["u"][0]), ("v", st["v"][0]), ("w_yaw", st["w_yaw"][0]),
                          ("pitch", st["pitch"][0]), ("roll", st["roll"][0]),
                          ("delta", delta)):
            rec[name].append(val)
        if k == n:
            break
        for j in range(substeps):
            car.substep(dt, F_z, F_d)
            if j == 0:
                for c, loads in car.corner_arm_loads().items():
                    for key, val in loads.items():
                        arm[c].setdefault(key, []).append(val)
    a = {k: np.asarray(v, dtype=float) for k, v in rec.items()}
    du, dv = np.gradient(a["u"], h), np.gradient(a["v"], h)
    return Histories(t=a["t"], F_z=a["F_z"], F_x=a["F_x"], F_y=a["F_y"], u=a["u"],
                     w_yaw=a["w_yaw"], a_x=du - a["v"] * a["w_yaw"],
                     a_y=dv + a["u"] * a["w_yaw"], pitch=a["pitch"], roll=a["roll"],
                     delta=a["delta"],
                     arm={c: {k: np.asarray(v) for k, v in d.items()} for c, d in arm.items()})
