"""The plant's coupled step without the bus: one copy, stepped by the plant node's shell
(:mod:`.node`, on a participant) and by the one-process engine
(:mod:`orchestrator.inprocess`, no bus at all).

Every step k (DESIGN.md "Lock-step co-simulation"): :meth:`PlantStepper.begin` gives the
time t_k and the state to publish; the force nodes answer with their forces of step k;
:meth:`PlantStepper.couple` applies them, takes the first substep and returns, as a function
to call later, the step's ``response`` (accelerations at t_k from PyBullet's forward
dynamics, the applied forces, the model's extra fields such as the bump-stop force ``F_bs``,
and the rates of the model's :meth:`~.model.PlantModel.response_velocities`) and, for
realistic models, its component loads; :meth:`PlantStepper.advance` integrates the remaining
substeps to t_{k+1}.

In the ``parallel`` exchange the forces of step k were computed from the state of step k-1
(one step of delay). With the ``jacobian`` coupling the plant linearises them about the state
they were computed from, F(x_k) ~ F_k + dF/dx (x_k - x_{k-1}): this removes the delay's
first-order error (all of it, for a linear tyre and damper).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from cosim import channels as ch
from cosim import node_kinds as nk
from cosim.errors import RunError
from cosim.run_settings import RunSettings
from cosim.step_size import step_residual
from cosim.wire import Message

from .coupling import StepInputs, substep_forces

Outputs = Callable[[], list[tuple[str, dict[str, Any]]]]
"""A coupled step's outputs [(channel, fields)], computed when called (:meth:`PlantStepper.
couple`)."""


class PlantStepper:
    """The plant's state between steps and its step (see the module's docstring).

    ``model`` is a :class:`~.model.PlantModel`; ``n`` the run's N (for ``run.h = "auto"``
    the bound t_end / h_min); ``start_k`` the first step (a resumed run's checkpoint)."""

    def __init__(self, model: Any, settings: RunSettings, n: int, start_k: int = 0) -> None:
        self.model, self.settings, self.n = model, settings, n
        self.h = settings.h
        self.ctrl = settings.adaptive  # run.h = "auto": the step is chosen as the run goes
        self.h_k = self.h if self.ctrl is None else self.ctrl.first  # this step's length [s]
        self.h_lin = self.h  # the last step's length: linear extrapolation's base [s]
        self.app_end: tuple[Any, Any] | None = None  # forces applied at the last step's end
        self.eps_prev: float | None = None
        self.k, self.t = start_k, start_k * self.h
        self.before: StepInputs | None = None
        self.prev = self.st = model.state()
        self._now: StepInputs | None = None
        self._after: dict[str, Any] | None = None
        self._dt = 0.0
        self.provides = dict(nk.force_sources())
        """Force node -> the coupling fields the plant takes from its ``force``."""

    # ---- checkpoints: {"model", "before", "prev", "st"} at the start of step k -----------
    def checkpoint(self) -> dict[str, Any]:
        """The whole state at the start of step :attr:`k`."""
        return {"model": self.model.checkpoint_state(), "before": self.before,
                "prev": self.prev, "st": self.st}

    def restore(self, saved: Mapping[str, Any]) -> None:
        """Continue from :meth:`checkpoint`."""
        self.model.restore_state(saved["model"])
        self.before, self.prev, self.st = saved["before"], saved["prev"], saved["st"]

    # ---- the step -------------------------------------------------------------------------
    def begin(self) -> tuple[int, float, dict[str, Any]]:
        """Step k, t_k [s] and the state at t_k (what the plant publishes first)."""
        if self.ctrl is None:
            self.t = self.k * self.h
        elif self.k > self.n:
            raise RunError(f"plant: step {self.k} at t = {self.t:.6g} s passes the bound "
                           f"{self.n} of t_end / h_min")
        return self.k, self.t, self.st

    def is_last(self) -> bool:
        """Whether the step begun is the run's last."""
        return self.settings.is_last(self.k, self.t)

    def couple(self, msgs: Mapping[str, Message]) -> Outputs:
        """Apply the forces of step k (``msgs``: force node -> its ``force`` message), take
        the first substep; the step's outputs [(channel, fields)] (``response``, loads) as a
        function that gives them, also after :meth:`advance`: what only the engine's present
        state holds is read now, the arithmetic at the call (the plant node sends the next
        state first: off the coupled chain's critical path, #41)."""
        model, st, ctrl = self.model, self.st, self.ctrl
        seen = self.prev if self.settings.lag else st  # what the forces were computed from
        forces = {f: m.array(f) for node, m in msgs.items() for f in self.provides[node]}
        road = msgs.get(ch.TYRE_ROAD)  # a 3-D tyre: Fx, Fy, Mz too
        if road is not None and "Fx" in road.d and hasattr(model, "set_tyre_forces"):
            model.set_tyre_forces(road.array("Fx"), road.array("Fy"), road.array("Mz"))
        now = StepInputs(F_t=forces["F_t"], k_t=forces["k_t"], F_d=forces["F_d"],
                         c_eff=forces["c_eff"], z_w=seen["z_w"],
                         v_rel=seen["v_w"] - seen["v_b"])
        if ctrl is not None:  # the last step's energy residual sets this one's length
            if self.app_end is not None:
                dE, carried = step_residual(self.app_end[0], now.F_t, st["v_w"],
                                            self.app_end[1], now.F_d, st["v_w"] - st["v_b"],
                                            self.h_lin)
                eps = ctrl.error(dE, carried)
                self.h_k, self.eps_prev = ctrl.next(self.h_lin, eps, self.eps_prev), eps
            if not self.is_last():  # (the last step's one substep: a_b, a_w)
                self.h_k = ctrl.clamp_to_end(self.h_k, self.t, self.settings.t_end)
        dt = self._dt = self.h_k / self.settings.substeps
        F_t, F_d = substep_forces(self.settings.coupling, now, self.before, 0.0, self.h_lin, st)
        F_s = model.spring_force()
        extra = model.extra_response()
        vel0 = model.response_velocities()
        model.substep(dt, F_t, F_d)
        after = model.state()
        vel1 = model.response_velocities()
        loads = model.loads_later()
        self._now, self._after = now, after

        def outputs() -> list[tuple[str, dict[str, Any]]]:
            response = {"a_b": (after["v_b"] - st["v_b"]) / dt,
                        "a_w": (after["v_w"] - st["v_w"]) / dt,
                        "F_t": F_t, "F_d": F_d, "F_s": F_s, **extra,
                        **{key: (vel1[key] - v) / dt for key, v in vel0.items()}}
            return [(ch.RESPONSE, response), *loads().items()]

        return outputs

    def advance(self) -> None:
        """The remaining substeps of step k to t_{k+1}; then step k + 1 is next."""
        now, cur = self._now, self._after
        assert now is not None and cur is not None, "advance before couple"
        mode, dt, model = self.settings.coupling, self._dt, self.model
        for j in range(1, self.settings.substeps):
            F_t, F_d = substep_forces(mode, now, self.before, j * dt, self.h_lin, cur)
            model.substep(dt, F_t, F_d)
            cur = model.state()
        if self.ctrl is not None:  # what the coupling applies at the step's end, and t_k+1
            self.app_end = substep_forces(mode, now, self.before, self.h_k, self.h_lin, cur)
            self.h_lin, self.t = self.h_k, self.t + self.h_k
        self.before, self.prev, self.st = now, self.st, cur  # cur: the state at t_{k+1}
        self._now = self._after = None
        self.k += 1
