"""The plant node: a PyBullet vehicle model on the bus.

Every step k: publish ``state`` at t_k; wait for ``tyre_road/force`` and ``controller/force``
of step k (the step barrier); take the first substep and publish ``response`` (accelerations
at t_k from PyBullet's forward dynamics, the applied forces, and the model's extra fields
such as the bump-stop force ``F_bs``, and the rates of the model's
:meth:`~.model.PlantModel.response_velocities`: arm-point or pitch/roll accelerations) and,
for realistic models, the
component loads (``arm``); integrate the remaining substeps to t_{k+1}.

In the ``parallel`` exchange the forces of step k were computed from the state of step k-1
(one step of delay). With the ``jacobian`` coupling the plant linearises them about the state
they were computed from, F(x_k) ~ F_k + dF/dx (x_k - x_{k-1}): this removes the delay's
first-order error (all of it, for a linear tyre and damper).
"""

from __future__ import annotations

from typing import Any, cast

from cosim import channels as ch
from cosim import node_kinds as nk
from cosim.errors import RunError
from cosim.participant import Participant
from cosim.run_checkpoint import NodeCheckpoints
from cosim.run_settings import RunSettings
from cosim.step_size import step_residual

from .coupling import StepInputs, substep_forces
from .models import build_plant_model


def run(part: Participant, scenario: dict[str, Any]) -> None:
    """Run the plant node until the last step (or until the run is aborted)."""
    settings = RunSettings.of(scenario)
    h, n_sub, mode, lag = settings.h, settings.substeps, settings.coupling, settings.lag
    model = build_plant_model(scenario["vehicle"])
    try:
        outputs = [ch.STATE, ch.RESPONSE, *model.loads().keys()]
        for name in outputs:
            part.output(name)
        # the force nodes of the registry, each with the coupling fields it provides
        sources = [part.listen(node, ch.FORCE, required=fields)
                   for node, fields in nk.force_sources()]
        provides = dict(nk.force_sources())
        info = dict(model.info(), outputs=outputs)
        plan = NodeCheckpoints.of(scenario, ch.PLANT)
        part.start_at(plan.start_k)
        start = part.handshake(info=info, timeout_s=settings.start_timeout_s)
        n = int(start["n_steps"])
        ctrl = settings.adaptive  # run.h = "auto": the step is chosen as the run goes
        if ctrl is not None and (lag or plan.due or plan.resuming):
            raise RunError("plant: run.h = 'auto' needs the sequential exchange and no "
                           "checkpoints (preflight should have said so)")
        h_k = h if ctrl is None else ctrl.first  # this step's length [s]
        h_lin = h  # the last step's length: linear extrapolation's base [s]
        app_end: tuple[Any, Any] | None = None  # forces applied at the last step's end
        eps_prev: float | None = None
        t = plan.start_k * h
        before: StepInputs | None = None
        later: list[tuple[str, int, float, dict]] = []
        prev = st = model.state()
        saved = plan.restored()
        if saved is not None:  # a resumed run: the state at the start of step start_k
            model.restore_state(saved["model"])
            before, prev, st = saved["before"], saved["prev"], saved["st"]
            if lag:  # the force nodes compute step start_k from the state of the step before
                part.publish(ch.STATE, plan.start_k - 1, (plan.start_k - 1) * h, prev,
                             record=False)
        k = plan.start_k
        while True:
            if ctrl is None:
                t = k * h
            elif k > n:
                raise RunError(f"plant: step {k} at t = {t:.6g} s passes the bound {n} of "
                               f"t_end / h_min")
            seen = prev if lag else st  # what the force nodes computed this step's forces from
            part.publish(ch.STATE, k, t, st)
            part.send()  # one message a step (#28): state k, the response and loads of k - 2
            # last step's response and loads: encoded while the force nodes compute, off the
            # coupled chain's critical path; they go out with state k + 1
            for name, kk, tt, values in later:
                part.publish(name, kk, tt, values, hold=True)
            later.clear()
            msgs = part.wait({tag: k for tag in sources})
            forces = {f: msg.array(f) for tag, msg in msgs.items() for f in provides[tag[0]]}
            road_plane = next((m for tag, m in msgs.items() if tag[0] == ch.TYRE_ROAD
                               and "Fx" in m.d), None)  # a 3-D tyre (#31): Fx, Fy, Mz too
            if road_plane is not None and hasattr(model, "set_tyre_forces"):
                model.set_tyre_forces(road_plane.array("Fx"), road_plane.array("Fy"),
                                      road_plane.array("Mz"))
            now = StepInputs(
                F_t=forces["F_t"], k_t=forces["k_t"], F_d=forces["F_d"],
                c_eff=forces["c_eff"], z_w=seen["z_w"], v_rel=seen["v_w"] - seen["v_b"],
            )
            if ctrl is not None:  # the last step's energy residual sets this one's length
                if app_end is not None:
                    dE, carried = step_residual(app_end[0], now.F_t, st["v_w"], app_end[1],
                                                now.F_d, st["v_w"] - st["v_b"], h_lin)
                    eps = ctrl.error(dE, carried)
                    h_k, eps_prev = ctrl.next(h_lin, eps, eps_prev), eps
                if not settings.is_last(k, t):  # (the last step's one substep: a_b, a_w)
                    h_k = ctrl.clamp_to_end(h_k, t, settings.t_end)
            dt = h_k / n_sub
            F_t, F_d = substep_forces(mode, now, before, 0.0, h_lin,
                                      st["z_w"], st["v_w"] - st["v_b"])
            F_s = model.spring_force()
            extra = model.extra_response()
            vel0 = model.response_velocities()
            model.substep(dt, F_t, F_d)
            after = model.state()
            vel1 = model.response_velocities()
            later.append((ch.RESPONSE, k, t, {
                "a_b": (after["v_b"] - st["v_b"]) / dt,
                "a_w": (after["v_w"] - st["v_w"]) / dt,
                "F_t": F_t, "F_d": F_d, "F_s": F_s, **extra,
                **{key: (vel1[key] - v) / dt for key, v in vel0.items()},
            }))
            later.extend((name, k, t, values) for name, values in model.loads().items())
            part.progress(k, t)
            if settings.is_last(k, t):
                for name, kk, tt, values in later:
                    part.publish(name, kk, tt, values)
                break
            cur = after
            for j in range(1, n_sub):
                F_t, F_d = substep_forces(mode, now, before, j * dt, h_lin,
                                          cur["z_w"], cur["v_w"] - cur["v_b"])
                model.substep(dt, F_t, F_d)
                cur = model.state()
            if ctrl is not None:  # what the coupling applies at the step's end, and t_k+1
                app_end = substep_forces(mode, now, before, h_k, h_lin,
                                         cur["z_w"], cur["v_w"] - cur["v_b"])
                h_lin, t = h_k, t + h_k
            before, prev, st = now, st, cur  # cur: the state at t_{k+1}
            if k + 1 in plan.due:  # checkpoint k + 1: steps <= k sent, then the state
                for name, kk, tt, values in later:
                    part.publish(name, kk, tt, values)
                later.clear()
                part.flush_records()
                plan.save(part, k + 1, {"model": model.checkpoint_state(), "before": before,
                                        "prev": prev, "st": st})
            k += 1
        part.finish(k, t)
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
