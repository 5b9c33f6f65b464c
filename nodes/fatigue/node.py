"""The fatigue node: damage of the lower arm computed while the run goes on.

It subscribes to the plant's load stream itself (``plant/arm``, :data:`cosim.channels.
LOAD_CHANNEL`: one message per step, as the scope does; Zenoh delivers a publisher's messages
reliably and in order, and a step missing or out of order is an error, never skipped),
gathers the steps into blocks of ``fatigue.block_samples`` counted from step 0, feeds each
block to :class:`LiveFatigue` (which screens: :mod:`.screening`), and publishes the damage so
far on ``fatigue/damage`` (any tap can follow the arm's projected life live). After the
run's last step it writes ``<run dir>/fatigue/`` (damage per node CSV, summary.json, damage
map PNG) — the same files, and the same numbers, as the batch ``suscosim fatigue RUN_DIR``
on the recorded table (the batch cuts the same blocks). docs/live_fatigue.md.
"""

from __future__ import annotations

import contextlib
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

from cosim import channels as ch
from cosim.errors import RunError, ScenarioError
from cosim.listener import Listener, Received
from cosim.load_blocks import StepBlocks
from cosim.participant import Participant
from cosim.run_checkpoint import NodeCheckpoints
from cosim.run_settings import RunSettings

from .config import FatigueConfig
from .run_dir import track_length, write_results
from .worker import FatigueResult, LiveFatigue, load_influence

REPORT_PERIOD_S = 0.5
"""At most this often (wall time) the damage so far is published on ``fatigue/damage``."""
NICE = 10
"""The node lowers its scheduling priority by this much (``os.nice``): it is off the coupled
chain's critical path (it takes the plant's steps as they come, in arrears), so on a 2-core
machine the plant, tyre/road and controller take the cores first and the fatigue node works in their
idle time; its numbers do not depend on when it runs."""


def run(part: Participant, scenario: dict[str, Any]) -> None:
    """Consume the plant's load steps until the last one, then write the run's results."""
    run_cfg = scenario["run"]
    cfg = FatigueConfig.from_dict(scenario.get("fatigue"))
    with contextlib.suppress(OSError):
        os.nice(NICE)
    load_influence(cfg)  # FE solve or cache read: before ready, not inside the run
    listener = Listener(part, run_cfg["start_timeout_s"])
    tag = listener.feed(ch.PLANT, cfg.load_channel)  # plant/arm, or a corner's arm_<C>
    part.output(ch.DAMAGE)
    early: list[Received] = []  # steps that overtook the start (another sender)
    while listener.start is None:  # the handshake
        if (got := listener.poll(timeout=0.05)) is not None:
            early.append(got)
    n_steps = int(listener.start["n_steps"])  # run.h = "auto": a bound; t says the last
    settings = RunSettings.of(scenario)
    adaptive = settings.adaptive is not None
    L = cfg.track_length_m if cfg.track_length_m is not None else \
        track_length(scenario, np.array([0.0, run_cfg["t_end"]]))
    steps = StepBlocks(max(1, cfg.block_samples))
    live: LiveFatigue | None = None
    next_k = 0
    t_last = 0.0
    plan = NodeCheckpoints.of(scenario, part.node)
    saved = plan.restored()
    if saved is not None:  # a resumed run: the engine after load step start_k - 1
        live, steps, next_k, t_last = (saved["live"], saved["steps"], saved["next_k"],
                                       saved["t_last"])
        if next_k != plan.start_k:
            raise RunError(f"fatigue: its checkpoint holds load steps < {next_k}, the run "
                           f"resumes at {plan.start_k}")
    last_input = time.monotonic()
    last_report = 0.0
    done = False
    while not done:
        got = early.pop(0) if early else listener.poll(timeout=0.05)  # raises on abort
        now = time.monotonic()
        if got is not None:
            k, t = got.msg.k, got.msg.t
            if k < next_k:  # a step already taken (a duplicate)
                part.reject(tag, f"load step {k} again")
                continue
            if k != next_k:
                raise RunError(f"fatigue: load step {k} came where step {next_k} was "
                               "expected (a step was lost)")
            try:
                steps.add(t, got.msg.d)
            except ValueError as exc:
                raise RunError(f"fatigue: malformed load step {k}: {exc}") from None
            next_k, t_last = k + 1, t
            last_input = now
            done = settings.is_last(k, t) or k >= n_steps
            if steps.full or done:
                if live is None:
                    live = LiveFatigue(cfg, [f"{ch.PLANT}/{ch.ARM}/{f}" for f in steps.fields],
                                       L, total_samples=None if adaptive else n_steps + 1)
                live.update(*steps.take())
                part.progress(k, t)
                if not done and now - last_report >= REPORT_PERIOD_S:
                    last_report = now
                    # residue closed: what the life would be if the run ended here
                    share = (t / settings.t_end if adaptive and settings.t_end > 0
                             else next_k / (n_steps + 1))
                    _report(part, live.result(), k, t_last, L * share)
            if next_k in plan.due:  # load steps < next_k taken: the engine and its buffer
                plan.save(part, next_k, {"live": live, "steps": steps, "next_k": next_k,
                                         "t_last": t_last})
        if now - last_input > max(30.0, 6.0 * part.stall_timeout_s):  # orchestrator gone too
            raise RunError(f"fatigue: no load step from the plant after step {next_k - 1}")
    assert live is not None
    result = live.result()
    result.source = "live"
    _report(part, result, next_k - 1, t_last, L)
    out = Path(run_cfg["dir"]) / "fatigue"
    write_results(result, out)
    part.finish(next_k - 1, t_last, min_life_km=_finite(result.life_km),
                min_life_repeats=_finite(result.life_repeats),
                max_damage=result.max_damage, critical_node_id=result.critical_node_id,
                files=str(out))


def _report(part: Participant, res: FatigueResult, k: int, t: float, distance_m: float) -> None:
    """The damage so far on ``fatigue/damage`` (a summary of recorded loads: not journaled)."""
    part.publish(ch.DAMAGE, k, t, {
        "max_damage": res.max_damage,
        "critical_node_id": res.critical_node_id,
        "distance_m": distance_m,
        "life_km": distance_m / res.max_damage / 1000.0 if res.max_damage > 0
        else float("inf"),
    }, record=False)


def _finite(x: float) -> float | str:
    return x if np.isfinite(x) else "inf"


def preflight(scenario: dict[str, Any], load_channels: list[str] | None) -> bool:
    """Preflight (:mod:`cosim.node_kinds`): validate ``[fatigue]``; whether the live fatigue
    node joins the run: ``fatigue.live = true``, or ``"auto"`` with a plant that publishes
    the lower-arm loads (``load_channels`` from the plant's check); never in reference
    mode. ``live = true`` without those loads is a ScenarioError."""
    cfg = FatigueConfig.from_dict(scenario.get("fatigue"))
    has_loads = cfg.load_channel in (load_channels or ())
    if cfg.live is True and not has_loads:
        raise ScenarioError("fatigue.live", True, "false or \"auto\": this vehicle model "
                            "reports no lower-arm loads (use the realistic corner)")
    return scenario["run"]["mode"] != "reference" and (
        cfg.live is True or (cfg.live == "auto" and has_loads))
