"""The plant node: a PyBullet vehicle model on the bus, its step :class:`.stepper.
PlantStepper` (the same one the one-process engine steps, :mod:`orchestrator.inprocess`).

Every step k: publish ``state`` at t_k; wait for ``tyre_road/force`` and ``controller/force``
of step k (the step barrier); take the first substep (:meth:`PlantStepper.couple`); integrate
the remaining substeps to t_{k+1} (:meth:`PlantStepper.advance`). The step's ``response`` and,
for realistic models, component loads (``arm``) are computed and encoded after state k + 1 has
gone out, while the force nodes compute step k + 1, and go out with state k + 2 (#28, #41).
"""

from __future__ import annotations

import os
from typing import Any, cast

from cosim import channels as ch
from cosim import node_kinds as nk
from cosim.errors import RunError
from cosim.participant import Participant
from cosim.run_checkpoint import NodeCheckpoints
from cosim.run_settings import RunSettings
from cosim.sink_window import SinkWindow, window_steps

from .models import build_plant_model
from .stepper import Outputs, PlantStepper

_yield = getattr(os, "sched_yield", lambda: None)


def run(part: Participant, scenario: dict[str, Any]) -> None:
    """Run the plant node until the last step (or until the run is aborted)."""
    settings = RunSettings.of(scenario)
    model = build_plant_model(scenario["vehicle"])
    try:
        outputs = [ch.STATE, ch.RESPONSE, *model.loads().keys()]
        for name in outputs:
            part.output(name)
        # the force nodes of the registry, each with the coupling fields it provides
        sources = [part.listen(node, ch.FORCE, required=fields)
                   for node, fields in nk.force_sources()]
        info = dict(model.info(), outputs=outputs)
        plan = NodeCheckpoints.of(scenario, ch.PLANT)
        part.start_at(plan.start_k)
        start = part.handshake(info=info, timeout_s=settings.start_timeout_s)
        if settings.adaptive is not None and (settings.lag or plan.due or plan.resuming):
            raise RunError("plant: run.h = 'auto' needs the sequential exchange and no "
                           "checkpoints (preflight should have said so)")
        plant = PlantStepper(model, settings, int(start["n_steps"]), plan.start_k)
        window_s = float(scenario["run"].get("sink_window_s", 0.0) or 0.0)
        sinks = SinkWindow(part, [n for n in scenario["run"]["nodes"]
                                  if nk.off_critical_path(n)],
                           window_steps(window_s, settings.h), plan.start_k)
        later: tuple[int, float, Outputs] | None = None  # last step's, not yet published

        def publish_later(hold: bool = False) -> None:
            if later is not None:
                kk, tt, outputs = later
                for name, values in outputs():
                    part.publish(name, kk, tt, values, hold=hold)

        saved = plan.restored()
        if saved is not None:  # a resumed run: the state at the start of step start_k
            with plan.restoring():  # a state that does not fit: exit 2 named (#43)
                plant.restore(saved)
            if settings.lag:  # the force nodes compute step start_k from the step before's
                k0 = plan.start_k - 1
                part.publish(ch.STATE, k0, k0 * settings.h, plant.prev, record=False)
        while True:
            k, t, st = plant.begin()
            sinks.hold(k)  # a sink more than run.sink_window_s behind: wait for it
            part.publish(ch.STATE, k, t, st)
            part.send()  # one message a step (#28): state k, the response and loads of k - 1
            _yield()  # a force node on this core takes it first (orchestrator/placement.py)
            # last step's response and loads: computed and encoded while the force nodes
            # compute, off the coupled chain's critical path; they go out with state k + 1
            publish_later(hold=True)
            msgs = part.wait({tag: k for tag in sources})
            later = (k, t, plant.couple({tag[0]: m for tag, m in msgs.items()}))
            part.progress(k, t)
            if plant.is_last():
                publish_later()
                break
            plant.advance()
            if plant.k in plan.due:  # checkpoint k + 1: steps <= k sent, then the state
                publish_later()
                later = None
                part.flush_records()
                plan.save(part, plant.k, plant.checkpoint())
        part.finish(k, t, sink_held_s=sinks.held_s)
    finally:
        model.close()


def preflight(scenario: dict[str, Any]) -> dict[str, Any]:
    """Preflight (:mod:`cosim.node_kinds`): build the vehicle model once (raises
    ScenarioError on a bad ``vehicle`` section); the facts the other checks take:
    ``n_corners`` and ``load_channels`` (the component-load channels it publishes)."""
    model = build_plant_model(scenario["vehicle"])
    try:
        info = model.info()
        return {"n_corners": int(cast(int, info["n_corners"])),
                "load_channels": sorted(model.loads())}
    finally:
        model.close()
