"""The fatigue node: damage of the lower arm computed while the run goes on.

It takes the plant's load stream from its records batches (``plant/records``), decodes only
the messages of its parts' load channels (``plant/arm``, :data:`cosim.channels.LOAD_CHANNEL`;
with ``[fatigue] parts`` also e.g. ``plant/upper_arm``), each against its channel's schema, and
hands them to :class:`.live_sink.LiveLoads` (blocks, engines, results: docs/live_fatigue.md).
Zenoh delivers a publisher's messages reliably and in order; a step missing or out of order is
an error, never skipped. The damage so far goes out on ``fatigue/damage``. Checkpoints with
more parts are refused (not supported yet).
"""

from __future__ import annotations

import contextlib
import os
import time
from typing import Any

from cosim import channels as ch
from cosim import keys
from cosim.errors import RunError, ScenarioError, WireError
from cosim.listener import Listener, Received
from cosim.load_blocks import StepBlocks
from cosim.participant import Participant, alive_while_busy
from cosim.run_checkpoint import NodeCheckpoints
from cosim.safe_open import check_user_file
from cosim.wire import codec, inner

from .config import FatigueConfig
from .lib.damage import SPECTRAL_METHODS
from .live_sink import LiveLoads, Track
from .more_parts import more_parts
from .worker import FatigueResult, LiveFatigue

REPORT_PERIOD_S = 0.5
"""At most this often (wall time) the damage so far is published on ``fatigue/damage``."""
HEARTBEAT_S = 1.0
"""While a block is computed, ``progress`` goes to the orchestrator this often [s] (wall)."""
NICE = 10
"""The node lowers its scheduling priority by this much (``os.nice``): it is off the coupled
chain's critical path (it takes the plant's steps in arrears), so the other nodes take the
cores first; its numbers do not depend on when it runs."""


def restore(tr: Track, saved: dict[str, Any], plan: NodeCheckpoints) -> None:
    """Put a checkpoint's state into the primary track ``tr``: its engine, buffered steps,
    next load step and last time. A state that does not fit (a key missing, a field of the
    wrong type) is a CheckpointError (exit 2) naming the node and the checkpoint
    (:meth:`NodeCheckpoints.restoring`); one of another step a RunError."""
    with plan.restoring():
        live, steps = saved["live"], saved["steps"]
        if not isinstance(live, LiveFatigue) or not isinstance(steps, StepBlocks):
            raise TypeError(f"'live' is a {type(live).__name__}, 'steps' a "
                            f"{type(steps).__name__} (a LiveFatigue and a StepBlocks expected)")
        tr.live, tr.steps = live, steps
        tr.next_k, tr.t_last = int(saved["next_k"]), float(saved["t_last"])
    if tr.next_k != plan.start_k:
        raise RunError(f"fatigue: its checkpoint holds load steps < {tr.next_k}, the "
                       f"run resumes at {plan.start_k}")


def run(part: Participant, scenario: dict[str, Any]) -> None:
    """Consume the plant's load steps until the last one, then write the run's results."""
    run_cfg = scenario["run"]
    with contextlib.suppress(OSError):
        os.nice(NICE)
    sink = LiveLoads(scenario)  # loads the influence coefficients: before ready
    tracks, main = sink.tracks, sink.main
    listener = Listener(part, run_cfg["start_timeout_s"])
    listener.feed(ch.PLANT, keys.RECORDS, kinds=("records",))
    codecs = {t.channel: codec(f"{ch.PLANT}/{t.channel}") for t in tracks}
    part.output(ch.DAMAGE)
    early: list[Received] = []  # steps that overtook the start (another sender)
    while listener.start is None:  # the handshake
        if (got := listener.poll(timeout=0.05)) is not None:
            early.append(got)
    sink.begin(int(listener.start["n_steps"]))  # run.h = "auto": a bound; t says the last
    plan = NodeCheckpoints.of(scenario, part.node)
    if len(tracks) > 1 and (plan.due or plan.resuming):
        raise RunError("fatigue: fatigue.parts with checkpoints (run.checkpoint_every_s, "
                       "resume) is not supported yet")
    saved = plan.restored()
    if saved is not None:  # a resumed run: the engine after load step start_k - 1
        restore(main, saved, plan)
    last_input = time.monotonic()
    last_report = 0.0

    def busy(k: int, t: float) -> contextlib.AbstractContextManager[None]:
        return alive_while_busy(part, k, t, HEARTBEAT_S)

    def take(tr: Track, k: int, t: float, d: dict[str, Any], now: float) -> None:
        """One load step of ``tr``'s channel, in step order."""
        nonlocal last_report
        try:
            computed = sink.take(tr, k, t, d, busy)
        except ValueError as exc:  # a step already taken (a duplicate)
            part.reject(tr.tag, str(exc))
            return
        if tr is main:  # the steps it has taken (rate-limited): the plant's window
            part.progress(k, t)  # counts them (cosim/sink_window.py)
        if computed and tr is main:
            assert tr.live is not None
            if not tr.done and now - last_report >= REPORT_PERIOD_S:
                last_report = now  # residue closed: the life if the run ended here
                _report(part, tr.live.result(), k, tr.t_last, sink.length_m * sink.share())
        if tr is main and tr.next_k in plan.due:  # load steps < next_k: engine, buffer
            plan.save(part, tr.next_k, {"live": tr.live, "steps": tr.steps,
                                        "next_k": tr.next_k, "t_last": tr.t_last})

    while not sink.done:
        got = early.pop(0) if early else listener.poll(timeout=0.05)  # raises on abort
        now = time.monotonic()
        if got is None:
            part.progress(main.next_k - 1, main.t_last)  # (rate-limited) idle: as far as it got
        else:
            for name, raw in inner(got.msg):  # the plant's messages as it published them
                tr = sink.by_channel.get(name)
                if tr is None:
                    continue  # not a load channel of a part here (state, response, ...)
                try:
                    msg = codecs[name].decode(raw)
                except WireError as exc:
                    part.reject(tr.tag, str(exc))
                    continue
                if msg.kind == "data":
                    take(tr, msg.k, msg.t, msg.d, now)
                    last_input = now
        if now - last_input > max(30.0, 6.0 * part.stall_timeout_s):  # orchestrator gone too
            late = [t for t in tracks if not t.done][0]
            raise RunError(f"fatigue: no load step from the plant on plant/{late.channel} "
                           f"after step {late.next_k - 1}")
    result, facts = sink.finish()
    _report(part, result, main.next_k - 1, main.t_last, sink.length_m)
    part.finish(main.next_k - 1, main.t_last, **facts)


def _report(part: Participant, res: FatigueResult, k: int, t: float, distance_m: float) -> None:
    """The damage so far on ``fatigue/damage`` (a summary of recorded loads: not journaled)."""
    part.publish(ch.DAMAGE, k, t, {
        "max_damage": res.max_damage,
        "critical_node_id": res.critical_node_id,
        "distance_m": distance_m,
        "life_km": distance_m / res.max_damage / 1000.0 if res.max_damage > 0
        else float("inf"),
    }, record=False)


def check_files(cfg: FatigueConfig) -> None:
    """Every file ``[fatigue]`` names is a regular file within its limit
    (:mod:`cosim.safe_open`), checked before the run: ``influence`` (a part file, a case
    table or a folder of them) and each ``mapping`` file, inside the influence folder."""
    if cfg.influence == "builtin":
        return
    path = cfg.influence_path
    if path.suffix.lower() == ".toml":
        check_user_file(path, "scenario", "fatigue.influence")
        return
    if not path.is_dir():
        check_user_file(path, "influence", "fatigue.influence")
    folder = path if path.is_dir() else path.parent
    for _, name, _ in cfg.mapping:
        check_user_file(folder / name, "influence", "fatigue.mapping", inside=folder)


def preflight(scenario: dict[str, Any], load_channels: list[str] | None) -> bool:
    """Preflight (:mod:`cosim.node_kinds`): validate ``[fatigue]``; whether the live fatigue
    node joins the run: ``fatigue.live = true``, or ``"auto"`` with a plant that publishes
    the lower-arm loads (``load_channels`` from the plant's check); never in reference
    mode. ``live = true`` without those loads is a ScenarioError."""
    cfg = FatigueConfig.from_dict(scenario.get("fatigue"))
    check_files(cfg)
    if cfg.method in SPECTRAL_METHODS:  # the PSD of the whole history: after the run
        if cfg.live is True:
            raise ScenarioError("fatigue.live", True, f"false or \"auto\" with method "
                                f"{cfg.method!r}: its PSD is of the whole history, computed "
                                "after the run by `suscosim fatigue RUN` (a sweep runs it)")
        return False
    has_loads = cfg.load_channel in (load_channels or ())
    if cfg.live is True and not has_loads:
        raise ScenarioError("fatigue.live", True, "false or \"auto\": this vehicle model "
                            "reports no lower-arm loads (use the realistic corner)")
    for mp in more_parts(cfg):  # each more part's loads must be published too
        if has_loads and mp.channel not in (load_channels or ()):
            raise ScenarioError("fatigue.parts", list(cfg.parts),
                                f"parts whose loads this vehicle model publishes (part "
                                f"{mp.name!r} takes plant/{mp.channel}; the plant publishes "
                                f"{', '.join(f'plant/{c}' for c in load_channels or ())})")
    return scenario["run"]["mode"] != "reference" and (
        cfg.live is True or (cfg.live == "auto" and has_loads))
