"""The contract every PyBullet plant model fulfils, so one plant node can drive any of them.

A plant model owns a PyBullet world (its own ``DIRECT`` client) holding the vehicle's rigid
bodies, joints and internal springs. It starts at **static equilibrium** (no settling run): the
internal springs carry their static preload, and the tyre force that balances gravity is
reported by :meth:`PlantModel.static_tyre_load` so the tyre node can add it.

Everything that crosses the bus is per **corner** (1 for a quarter car; 4 for a full vehicle in
the order FL, FR, RL, RR), in SI units, ISO 8855 axes (z up), displacements from static
equilibrium:

* inputs, held (or extrapolated by the plant node) over a substep:
  ``F_t`` tyre force on the wheel, compressive-positive, >= 0 [N];
  ``F_d`` damper force on the body at the corner, upward positive; the wheel gets ``-F_d`` [N].
* state: ``z_b`` body displacement at the corner [m], ``v_b`` [m/s], ``z_w`` wheel centre
  displacement [m], ``v_w`` [m/s]; full-vehicle models add ``heave`` [m], ``pitch``, ``roll``
  [rad], ``v_heave`` [m/s], ``w_pitch``, ``w_roll`` [rad/s] (arrays of length 1).
* loads: component loads the fatigue worker superposes, e.g. ``arm`` -> {``ball_joint_x``: N,...}.
"""

from __future__ import annotations

import copy
import tempfile
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from . import quiet_pybullet  # noqa: F401 - pybullet imported without its banner, first
from .quiet_pybullet import p

GRAVITY = 9.81
"""g [m/s^2], the value the thesis uses."""


class PlantModel(ABC):
    """A vehicle model in PyBullet that the plant's stepper (:mod:`.stepper`) steps: each step
    ``state()``, ``spring_force()``, ``extra_response()``, ``response_velocities()``, then
    ``substep`` n times with the coupling's forces, ``loads()`` after the first."""

    n_corners: int = 1
    name: str = "plant"

    @abstractmethod
    def static_tyre_load(self) -> np.ndarray:
        """Static vertical tyre load per corner [N] (what balances gravity at equilibrium)."""

    @abstractmethod
    def state(self) -> dict[str, np.ndarray]:
        """Current state; keys ``z_b, v_b, z_w, v_w`` (per corner) at least."""

    @abstractmethod
    def spring_force(self) -> np.ndarray:
        """Suspension spring force per corner on the body, upward positive, dynamic part [N]."""

    @abstractmethod
    def substep(self, dt: float, F_t: np.ndarray, F_d: np.ndarray) -> None:
        """Apply the tyre and damper forces (held during ``dt``) and integrate ``dt`` seconds."""

    def extra_response(self) -> dict[str, np.ndarray]:
        """Model-specific fields of ``plant/response`` at t_k per corner (e.g. the bump-stop
        force ``F_bs`` [N]); empty by default."""
        return {}

    def response_velocities(self) -> Mapping[str, np.ndarray | float]:
        """Velocities keyed by the acceleration field of ``plant/response`` the node derives as
        ``(after - before) / dt`` over the first substep (e.g. ``a_arm_loc1_z`` [m/s^2],
        ``alpha_pitch`` [rad/s^2]), per corner or length 1; empty by default."""
        return {}

    def loads(self) -> dict[str, dict[str, float]]:
        """Component loads after the latest substep, by channel, e.g. ``{"arm": {...}}``."""
        return self.loads_later()()

    def loads_later(self) -> Callable[[], dict[str, dict[str, float]]]:
        """:meth:`loads` as a function to call after more substeps: what only the physics
        engine's present state holds is read now, the rest is computed at the call (the
        plant node publishes the next state first, off its critical path: #41). None here."""
        return dict

    def info(self) -> dict[str, object]:
        """Static facts other nodes need at start (sent in the ready handshake)."""
        return {"n_corners": self.n_corners,
                "static_tyre_load": [float(x) for x in self.static_tyre_load()]}

    checkpoint_keep: tuple[str, ...] = ("client",)
    """Attributes :meth:`restore_state` leaves as they are: the PyBullet client of this
    process (a fresh model's id may differ; body and joint ids do not, the world being built
    the same way from the same scenario)."""

    def checkpoint_state(self) -> dict[str, Any]:
        """The model's whole state at a step boundary, plain data
        (:mod:`cosim.plaindata`): the PyBullet world as ``saveBullet`` writes it (positions,
        velocities, the solver's state) and a deep copy of the model's own attributes
        (integrator memory, the driver, held tyre forces, the last loads) but
        :attr:`checkpoint_keep`."""
        client = getattr(self, "client", None)
        if client is None:
            raise TypeError(f"{type(self).__name__} has no PyBullet client to checkpoint")
        with tempfile.TemporaryDirectory(prefix="suscosim-ckpt-") as folder:
            path = Path(folder) / "world.bullet"
            p.saveBullet(str(path), physicsClientId=client)
            world = path.read_bytes()
        attrs = {k: copy.deepcopy(v) for k, v in vars(self).items()
                 if k not in self.checkpoint_keep}
        # the engine's settings are not in a .bullet file (a model sets its time step lazily)
        engine = p.getPhysicsEngineParameters(physicsClientId=client)
        return {"model": self.name, "bullet": world, "attrs": attrs, "engine": engine}

    def restore_state(self, state: dict[str, Any]) -> None:
        """Continue from :meth:`checkpoint_state` of a model built from the same scenario:
        the next substeps are the checkpointed model's, bit for bit (tested per model).
        Raises ValueError when the state is another model's."""
        if state.get("model") != self.name:
            raise ValueError(f"a checkpoint of plant model {state.get('model')!r} cannot "
                             f"restore a {self.name!r}")
        client = getattr(self, "client")  # noqa: B009 - every PyBullet model has one
        with tempfile.TemporaryDirectory(prefix="suscosim-ckpt-") as folder:
            path = Path(folder) / "world.bullet"
            path.write_bytes(state["bullet"])
            p.restoreState(fileName=str(path), physicsClientId=client)
        e = state["engine"]
        p.setGravity(e["gravityAccelerationX"], e["gravityAccelerationY"],
                     e["gravityAccelerationZ"], physicsClientId=client)
        p.setPhysicsEngineParameter(
            fixedTimeStep=e["fixedTimeStep"], numSubSteps=e["numSubSteps"],
            numSolverIterations=e["numSolverIterations"],
            numNonContactInnerIterations=e["numNonContactInnerIterations"],
            physicsClientId=client)
        for k, v in state["attrs"].items():
            setattr(self, k, copy.deepcopy(v))

    def close(self) -> None:
        """Release the PyBullet client (``client``), if the model has one."""
        client = getattr(self, "client", None)
        if client is not None and p.isConnected(client):
            p.disconnect(client)
