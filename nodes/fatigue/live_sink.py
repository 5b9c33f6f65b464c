"""The live fatigue node's work without the bus: the plant's load steps in, the run's fatigue
results out. One copy, used by the node's shell (:mod:`.node`, on a participant) and by the
one-process engine (:mod:`orchestrator.inprocess`), so both give the same files and numbers.

:class:`LiveLoads` holds one track per part (the primary's load channel, ``plant/arm`` or a
corner's, and each ``[fatigue] parts`` part's): a track takes its channel's steps in order
(a step missing or out of order is an error, never skipped), gathers them into blocks of
``fatigue.block_samples`` counted from step 0, and feeds each block to :class:`LiveFatigue`.
After the run's last step :meth:`LiveLoads.finish` writes ``<run dir>/fatigue/``
(docs/live_fatigue.md).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from cosim import channels as ch
from cosim.errors import RunError
from cosim.load_blocks import StepBlocks
from cosim.run_settings import RunSettings

from .config import FatigueConfig
from .more_parts import column_names, load_channel, more_parts, part_channels
from .run_dir import part_entry, parts_summary, track_length, with_parts, write_results
from .worker import FatigueResult, LiveFatigue, load_influence


class Track:
    """One part's load stream: its channel's steps in order, blocks, engine."""

    def __init__(self, name: str | None, cfg: FatigueConfig, channel: str,
                 cases: list[str]) -> None:
        self.name, self.cfg, self.channel, self.cases = name, cfg, channel, cases
        self.tag = (ch.PLANT, channel)
        self.steps = StepBlocks(max(1, cfg.block_samples))
        self.live: LiveFatigue | None = None
        self.next_k = 0
        self.t_last = 0.0
        self.done = False

    def columns(self, fields: list[str]) -> list[str]:
        """The load columns' names (:func:`.more_parts.column_names`)."""
        return column_names(self.channel, fields, self.cases)


class LiveLoads:
    """Every part's track of one run (see the module's docstring). Built before the start
    (it loads the influence coefficients: an FE solve or a cache read); :meth:`begin` once
    N is known; :meth:`take` each load step; :meth:`finish` after the last."""

    def __init__(self, scenario: dict[str, Any]) -> None:
        self.scenario = scenario
        self.cfg = cfg = FatigueConfig.from_dict(scenario.get("fatigue"))
        extras = more_parts(cfg)
        load_influence(cfg)  # FE solve or cache read: before ready, not inside the run
        for mp in extras:
            load_influence(mp.cfg)
        self.tracks = [Track(None, cfg, load_channel(cfg), part_channels(cfg))]
        self.tracks += [Track(mp.name, mp.cfg, mp.channel, mp.cases) for mp in extras]
        self.by_channel = {t.channel: t for t in self.tracks}
        if len(self.by_channel) != len(self.tracks):
            raise RunError("fatigue: fatigue.parts: two parts on one load channel "
                           f"({', '.join(sorted({t.channel for t in self.tracks}))}) are not "
                           "supported yet")
        self.main = self.tracks[0]
        self.n_steps = 0
        self.settings = RunSettings.of(scenario)
        self.length_m = 0.0

    def begin(self, n_steps: int) -> None:
        """The run's N (for ``run.h = "auto"`` a bound: t says which step is the last)."""
        run_cfg = self.scenario["run"]
        self.n_steps = n_steps
        cfg = self.cfg
        self.length_m = cfg.track_length_m if cfg.track_length_m is not None else \
            track_length(self.scenario, np.array([0.0, run_cfg["t_end"]]))

    @property
    def done(self) -> bool:
        """Every track has taken the run's last step."""
        return all(t.done for t in self.tracks)

    def take(self, tr: Track, k: int, t: float, d: dict[str, Any],
             busy: Callable[[int, float], Any] | None = None) -> bool:
        """One load step of ``tr``'s channel, in step order; whether a block was computed.
        A step already taken is ignored (False; the shell counts it); ``busy(k, t)``: a
        context manager held while a block is computed (the node's heartbeat)."""
        if k < tr.next_k:
            raise ValueError(f"load step {k} again")
        if k != tr.next_k:
            raise RunError(f"fatigue: load step {k} of plant/{tr.channel} came where "
                           f"step {tr.next_k} was expected (a step was lost)")
        try:
            tr.steps.add(t, d)
        except ValueError as exc:
            raise RunError(f"fatigue: malformed load step {k}: {exc}") from None
        tr.next_k, tr.t_last = k + 1, t
        tr.done = self.settings.is_last(k, t) or k >= self.n_steps
        if not (tr.steps.full or tr.done):
            return False
        if tr.live is None:
            adaptive = self.settings.adaptive is not None
            tr.live = LiveFatigue(tr.cfg, tr.columns(tr.steps.fields), self.length_m,
                                  screen=tr.cfg.screen or None,
                                  total_samples=None if adaptive else self.n_steps + 1)
        if busy is None:
            tr.live.update(*tr.steps.take())
        else:
            with busy(k, t):
                tr.live.update(*tr.steps.take())
        return True

    def share(self) -> float:
        """The share of the run the primary track has taken (0..1)."""
        s, tr = self.settings, self.main
        if s.adaptive is not None and s.t_end > 0:
            return tr.t_last / s.t_end
        return tr.next_k / (self.n_steps + 1)

    def finish(self) -> tuple[FatigueResult, dict[str, Any]]:
        """Write ``<run dir>/fatigue/``; the primary result and the node's ``done`` facts."""
        main = self.main
        assert main.live is not None
        result = main.live.result()
        result.source = "live"
        out = Path(self.scenario["run"]["dir"]) / "fatigue"
        more: list[tuple[str, FatigueResult, dict, Any]] = []
        entries = []
        for tr in self.tracks[1:]:
            assert tr.live is not None and tr.name is not None
            r = tr.live.result()
            r.source = "live"
            more.append((tr.name, r, {}, None))
            entries.append(part_entry(tr.name, tr.name, tr.channel, r, tr.cfg.influence))
        extra = {"parts": parts_summary(self.cfg, result, None, entries)} if more else None
        write_results(result, out, extra, with_parts(None, more))
        info: dict[str, Any] = {}
        if more:
            info["parts"] = {name: {"min_life_km": finite(r.life_km),
                                    "critical_node_id": r.critical_node_id,
                                    "files": str(out / name)} for name, r, _, _ in more}
        return result, dict(min_life_km=finite(result.life_km),
                            min_life_repeats=finite(result.life_repeats),
                            max_damage=result.max_damage,
                            critical_node_id=result.critical_node_id, files=str(out), **info)


def finite(x: float) -> float | str:
    return x if np.isfinite(x) else "inf"
