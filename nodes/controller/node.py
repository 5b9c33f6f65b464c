"""The controller node: damper model and semi-active control law on the bus.

Every step k it waits for the plant's ``state`` (of step k in the sequential exchange, of
step k-1 in the parallel one), runs the law, and publishes ``force``: F_d [N] (on the body,
upward positive), c_eff = dF_d/d(v_w - v_b) [N s/m] for the plant's coupling, and the law's
extras (MR current, switching state...). ``velocity = "damper"``: :mod:`.base`; a plant
without ``v_damper`` then ends the run with a clear error.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from cosim import channels as ch
from cosim.errors import RunError, ScenarioError

from .laws import build_controller

STATE = f"{ch.PLANT}/{ch.STATE}"


class Controller:
    """The controller node as a stepped class (the shell: :func:`cosim.stepped.run_stepped`)."""

    FIELDS = {STATE: ch.STATE_FIELDS}
    """What it needs of its input (the law may read more: ``v_damper``...)."""

    def __init__(self, scenario: dict[str, Any], start: dict[str, Any]) -> None:
        self.plant = start["info"][ch.PLANT]
        self.law = build_controller(scenario["controller"], int(self.plant["n_corners"]),
                                    scenario["run"]["h"])
        self._restore: dict[str, Any] | None = None

    # ---- checkpoints (the shell calls these, cosim.stepped) -----------------------------
    def checkpoint_refusal(self) -> str | None:
        """Why this law's state cannot be checkpointed (an FMU without FMI state
        serialisation), or None."""
        plan = getattr(self.law, "plan", None)
        refusal = getattr(plan, "checkpoint_refusal", None)
        return refusal() if callable(refusal) else None

    def checkpoint_state(self) -> dict[str, Any]:
        """The law's whole state at a step boundary (:meth:`ControlLaw.checkpoint_state`);
        one not yet put back (a checkpoint taken before the first step after a resume) is
        the state still pending."""
        return self._restore if self._restore is not None else self.law.checkpoint_state()

    def restore_state(self, state: dict[str, Any]) -> None:
        """Continue from :meth:`checkpoint_state`: put back at the next step, which gives
        the time and the plant's state a law that must start something (an FMU) needs."""
        self._restore = state

    def step(self, k: int, t: float, inputs: Mapping[str, Mapping[str, np.ndarray]]
             ) -> dict[str, Any]:
        """F_d, c_eff and the law's extras of step k from the plant's state."""
        values = inputs[STATE]
        law = self.law
        if self._restore is not None:
            try:
                law.restore_state(self._restore, t, values)
            except (ValueError, KeyError, TypeError, AttributeError) as exc:
                from cosim.checkpoint import CheckpointError  # exit 2, never internal

                raise CheckpointError(f"controller: the law's state in the checkpoint does "
                                      f"not fit it: {exc}") from None
            self._restore = None
        if law.velocity == "damper" and "v_damper" not in values:
            model = self.plant.get("model", "?")
            raise RunError(f"controller.velocity = 'damper' but the plant model '{model}' "
                           "publishes no v_damper (only the double-wishbone corner does)")
        out = law.step(t, values)
        c_eff = law.plant_slope(out.c_eff, values)
        return {"F_d": out.F_d, "c_eff": c_eff, **out.extra}

    def close(self) -> None:
        self.law.close()  # an FMU law terminates and frees its instances


#: Plant models whose state carries ``v_damper`` (for ``controller.velocity = "damper"``).
DAMPER_VELOCITY_MODELS = ("quarter_car_double_wishbone", "full_vehicle_double_wishbone")


def static_check(scenario: dict[str, Any], n_corners: int) -> None:
    """Preflight: build the law once (raises ScenarioError on a bad ``controller`` section,
    or on ``velocity = "damper"`` with a plant model that has no damper velocity)."""
    law = build_controller(scenario["controller"], n_corners, scenario["run"]["h"])
    try:
        if scenario["run"].get("adaptive") and law.fixed_step:
            raise ScenarioError("run.h", "auto", f"a fixed step for controller.law = "
                                f"{law.law!r}: it integrates a state with a fixed step")
    finally:
        law.close()
    model = scenario.get("vehicle", {}).get("model")
    if law.velocity == "damper" and model not in DAMPER_VELOCITY_MODELS:
        raise ScenarioError("controller.velocity", "damper",
                            f"'relative' for vehicle.model = {model!r} (only "
                            f"{', '.join(DAMPER_VELOCITY_MODELS)} publishes v_damper)")


def fmu_check(scenario: dict[str, Any], n_corners: int) -> None:
    """Preflight of ``[nodes] controller = "fmu"`` (the registry's FMU alternative of the
    controller): the law is the FMU (``controller.law = "fmu"``, filled in when absent; any
    other law is a ScenarioError), then :func:`static_check` opens the FMU and checks its
    model description."""
    section = scenario.setdefault("controller", {})
    law = section.setdefault("law", "fmu")
    if law != "fmu":
        raise ScenarioError("controller.law", law, "\"fmu\" (or no law) with [nodes] "
                            "controller = \"fmu\"")
    static_check(scenario, n_corners)
