"""The fatigue node: damage of the lower arm computed while the run goes on.

It takes the plant's load stream itself, from the plant's records batches
(``plant/records``: the plant's data messages as published, a batch every 64 messages or
50 ms, so one delivery and one signature check per batch instead of per step; it decodes only
the messages of its load channel, ``plant/arm`` (:data:`cosim.channels.LOAD_CHANNEL`), each
against its channel's schema; Zenoh delivers a publisher's messages reliably and in order,
and a step missing or out of order is an error, never skipped),
gathers the steps into blocks of ``fatigue.block_samples`` counted from step 0, feeds each
block to :class:`LiveFatigue` (which screens: :mod:`.screening`), and publishes the damage so
far on ``fatigue/damage`` (any tap can follow the arm's projected life live). After the
run's last step it writes ``<run dir>/fatigue/`` (damage per node CSV, summary.json, damage
map PNG) — the same files, and the same numbers, as the batch ``suscosim fatigue RUN_DIR``
on the recorded table (the batch cuts the same blocks). docs/live_fatigue.md.

With ``[fatigue] parts`` (:mod:`.more_parts`) it also subscribes to each more part's load
channel (the upper arm's ``plant/upper_arm``), runs an engine per part on the same blocks,
and writes each part's files to ``<run dir>/fatigue/<part name>/`` inside the same folder
(renamed into place with it), the primary ``summary.json``'s ``parts`` naming them all.
Checkpoints with more parts are refused (not supported yet).
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from cosim import channels as ch
from cosim import keys
from cosim.errors import RunError, ScenarioError, WireError
from cosim.listener import Listener, Received
from cosim.load_blocks import StepBlocks
from cosim.participant import Participant
from cosim.run_checkpoint import NodeCheckpoints
from cosim.run_settings import RunSettings
from cosim.wire import codec, inner

from .config import FatigueConfig
from .more_parts import (
    UPPER_ARM,
    column_names,
    load_channel,
    more_parts,
    part_channels,
    primary_name,
)
from .run_dir import part_entry, track_length, with_parts, write_results
from .worker import FatigueResult, LiveFatigue, load_influence

REPORT_PERIOD_S = 0.5
"""At most this often (wall time) the damage so far is published on ``fatigue/damage``."""
HEARTBEAT_S = 1.0
"""While a block is computed, ``progress`` goes to the orchestrator this often [s] (wall)."""
NICE = 10
"""The node lowers its scheduling priority by this much (``os.nice``): it is off the coupled
chain's critical path (it takes the plant's steps as they come, in arrears), so on a 2-core
machine the plant, tyre/road and controller take the cores first and the fatigue node works in their
idle time; its numbers do not depend on when it runs."""


class _Track:
    """One part's load stream: its channel's steps in order, blocks, engine."""

    def __init__(self, name: str | None, cfg: FatigueConfig, channel: str, tag: Any,
                 cases: list[str]) -> None:
        self.name, self.cfg, self.channel, self.tag, self.cases = name, cfg, channel, tag, cases
        self.steps = StepBlocks(max(1, cfg.block_samples))
        self.live: LiveFatigue | None = None
        self.next_k = 0
        self.t_last = 0.0
        self.done = False

    def columns(self, fields: list[str]) -> list[str]:
        """The load columns' names (the primary's as before: ``plant/arm/<field>``)."""
        if self.channel != UPPER_ARM:
            return [f"{ch.PLANT}/{ch.ARM}/{f}" for f in fields]
        return column_names(self.channel, fields, self.cases)


def run(part: Participant, scenario: dict[str, Any]) -> None:
    """Consume the plant's load steps until the last one, then write the run's results."""
    run_cfg = scenario["run"]
    cfg = FatigueConfig.from_dict(scenario.get("fatigue"))
    extras = more_parts(cfg)
    with contextlib.suppress(OSError):
        os.nice(NICE)
    load_influence(cfg)  # FE solve or cache read: before ready, not inside the run
    for mp in extras:
        load_influence(mp.cfg)
    listener = Listener(part, run_cfg["start_timeout_s"])
    listener.feed(ch.PLANT, keys.RECORDS, kinds=("records",))
    # plant/arm, or a corner's arm_<C> (or the upper arm's, for an upper-arm primary part)
    channel = load_channel(cfg)
    tracks = [_Track(None, cfg, channel, (ch.PLANT, channel), part_channels(cfg))]
    tracks += [_Track(mp.name, mp.cfg, mp.channel, (ch.PLANT, mp.channel), mp.cases)
               for mp in extras]
    by_channel = {t.channel: t for t in tracks}
    codecs = {t.channel: codec(f"{ch.PLANT}/{t.channel}") for t in tracks}
    if len(by_channel) != len(tracks):
        raise RunError("fatigue: fatigue.parts: two parts on one load channel "
                       f"({', '.join(sorted({t.channel for t in tracks}))}) are not "
                       "supported yet")
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
    main = tracks[0]
    plan = NodeCheckpoints.of(scenario, part.node)
    if extras and (plan.due or plan.resuming):
        raise RunError("fatigue: fatigue.parts with checkpoints (run.checkpoint_every_s, "
                       "resume) is not supported yet")
    saved = plan.restored()
    if saved is not None:  # a resumed run: the engine after load step start_k - 1
        main.live, main.steps, main.next_k, main.t_last = (
            saved["live"], saved["steps"], saved["next_k"], saved["t_last"])
        if main.next_k != plan.start_k:
            raise RunError(f"fatigue: its checkpoint holds load steps < {main.next_k}, the "
                           f"run resumes at {plan.start_k}")
    last_input = time.monotonic()
    last_report = 0.0

    def take(tr: _Track, k: int, t: float, d: dict[str, Any], now: float) -> None:
        """One load step of ``tr``'s channel, in step order."""
        nonlocal last_report
        if k < tr.next_k:  # a step already taken (a duplicate)
            part.reject(tr.tag, f"load step {k} again")
            return
        if k != tr.next_k:
            raise RunError(f"fatigue: load step {k} of plant/{tr.channel} came where "
                           f"step {tr.next_k} was expected (a step was lost)")
        try:
            tr.steps.add(t, d)
        except ValueError as exc:
            raise RunError(f"fatigue: malformed load step {k}: {exc}") from None
        tr.next_k, tr.t_last = k + 1, t
        tr.done = settings.is_last(k, t) or k >= n_steps
        if tr.steps.full or tr.done:
            if tr.live is None:
                tr.live = LiveFatigue(tr.cfg, tr.columns(tr.steps.fields), L,
                                      screen=tr.cfg.screen or None,
                                      total_samples=None if adaptive else n_steps + 1)
            with alive_while_busy(part, k, t):
                tr.live.update(*tr.steps.take())
            if tr is main:
                part.progress(k, t)
            if tr is main and not tr.done and now - last_report >= REPORT_PERIOD_S:
                last_report = now
                # residue closed: what the life would be if the run ended here
                share = (t / settings.t_end if adaptive and settings.t_end > 0
                         else tr.next_k / (n_steps + 1))
                _report(part, tr.live.result(), k, tr.t_last, L * share)
        if tr is main and tr.next_k in plan.due:  # load steps < next_k: engine, buffer
            plan.save(part, tr.next_k, {"live": tr.live, "steps": tr.steps,
                                        "next_k": tr.next_k, "t_last": tr.t_last})

    while not all(t.done for t in tracks):
        got = early.pop(0) if early else listener.poll(timeout=0.05)  # raises on abort
        now = time.monotonic()
        if got is not None:
            for name, raw in inner(got.msg):  # the plant's messages as it published them
                tr = by_channel.get(name)
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
    assert main.live is not None
    result = main.live.result()
    result.source = "live"
    _report(part, result, main.next_k - 1, main.t_last, L)
    out = Path(run_cfg["dir"]) / "fatigue"
    more: list[tuple[str, FatigueResult, dict, Any]] = []
    entries = []
    for tr in tracks[1:]:
        assert tr.live is not None and tr.name is not None
        r = tr.live.result()
        r.source = "live"
        more.append((tr.name, r, {}, None))
        entries.append(part_entry(tr.name, tr.name, tr.channel, r, tr.cfg.influence))
    extra = None
    if more:
        extra = {"parts": [part_entry(primary_name(cfg), ".", main.channel, result,
                                      None if cfg.influence.startswith("builtin")
                                      else cfg.influence), *entries]}
    write_results(result, out, extra, with_parts(None, more))
    info: dict[str, Any] = {}
    if more:
        info["parts"] = {name: {"min_life_km": _finite(r.life_km),
                                "critical_node_id": r.critical_node_id,
                                "files": str(out / name)} for name, r, _, _ in more}
    part.finish(main.next_k - 1, main.t_last, min_life_km=_finite(result.life_km),
                min_life_repeats=_finite(result.life_repeats),
                max_damage=result.max_damage, critical_node_id=result.critical_node_id,
                files=str(out), **info)


@contextlib.contextmanager
def alive_while_busy(part: Participant, k: int, t: float,
                     period_s: float = HEARTBEAT_S) -> Iterator[None]:
    """Tell the orchestrator every ``period_s`` that this node is working on load step ``k``
    while the block inside runs. A block of the CAD arm that starts at rest keeps nearly every
    sample (a constant history cannot be proven monotone: ~4 ms a step, measured on a 0.4 s
    run), so at nice +10 on a loaded machine its computation can outlast a short run's stall
    timeout (5 s by default) and the clock would blame a node that is computing. Only while
    the block runs: a node stuck anywhere else is still seen as stalled."""
    done = threading.Event()

    def beat() -> None:
        while not done.wait(period_s):
            try:
                part.ctl("progress", k, t, rejected=part.rejected)
            except Exception:  # the session is closing: the main thread will say why
                return

    th = threading.Thread(target=beat, daemon=True, name="fatigue-heartbeat")
    th.start()
    try:
        yield
    finally:
        done.set()
        th.join()


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
    for mp in more_parts(cfg):  # each more part's loads must be published too
        if has_loads and mp.channel not in (load_channels or ()):
            raise ScenarioError("fatigue.parts", list(cfg.parts),
                                f"parts whose loads this vehicle model publishes (part "
                                f"{mp.name!r} takes plant/{mp.channel}; the plant publishes "
                                f"{', '.join(f'plant/{c}' for c in load_channels or ())})")
    return scenario["run"]["mode"] != "reference" and (
        cfg.live is True or (cfg.live == "auto" and has_loads))
