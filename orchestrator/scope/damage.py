"""The scope's damage map, computed from the ``plant/arm`` loads with the live fatigue node's
own engine (:class:`nodes.fatigue.worker.LiveFatigue`), so its last step's largest damage is the
run's ``max_damage_per_pass``; a scope that joins late reads the missed steps from the journal.
Damage per node [-] (Miner, per pass so far, residue closed) sent as log10; positions [mm].
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from cosim import channels as ch
from cosim.wire import Message

from .state import ScopeState

UPDATE_PERIOD_S = 0.5  # [s] of wall time between recomputations of the map
BACKFILL_TRIES = 20  # reads of the journal for missed steps before drawing from the join


def wants_map(scenario: dict[str, Any] | None) -> bool:
    run = (scenario or {}).get("run") or {}
    return "fatigue" in (run.get("nodes") or [])


class DamageMap:
    """Feed ``plant/arm`` messages in step order; the map lands in ``state``."""

    def __init__(self, scenario: dict[str, Any], state: ScopeState,
                 period_s: float = UPDATE_PERIOD_S, journal: Path | None = None) -> None:
        from nodes.fatigue.config import FatigueConfig
        from nodes.fatigue.run_dir import track_length

        run = scenario["run"]
        self.cfg = FatigueConfig.from_dict(scenario.get("fatigue"))
        self.n_steps = int(run.get("n_steps") or round(run["t_end"] / run["h"]))
        self.track_m = self.cfg.track_length_m if self.cfg.track_length_m is not None else \
            track_length(scenario, np.array([0.0, float(run["t_end"])]))
        self.state, self.period_s = state, period_s
        self._live: Any = None
        self._fields: list[str] = []
        self._t: list[float] = []
        self._rows: list[list[float]] = []
        self.k0: int | None = None
        self.next_k = 0
        self.gaps = 0
        self._last = 0.0
        self.problem = ""
        self.journal = journal
        self._backfill_tries = 0 if journal is not None else BACKFILL_TRIES
        self.backfilled = 0

    def push(self, msg: Message, now: float | None = None) -> None:
        if msg.k < 0 or self.problem:
            return
        if self.k0 is None:
            self.k0 = self.next_k = msg.k
            self._fields = [f for f, v in msg.d.items() if isinstance(v, int | float)]
        if msg.k < self.next_k:
            return  # a repeat
        if msg.k > self.next_k:
            self.gaps += msg.k - self.next_k
        try:
            self._rows.append([float(msg.d[f]) for f in self._fields])
        except (KeyError, TypeError, ValueError):
            return
        self._t.append(msg.t)
        self.next_k = msg.k + 1
        now = time.monotonic() if now is None else now
        if msg.k >= self.n_steps or now - self._last >= self.period_s:
            self._last = now
            self.flush()

    def flush(self) -> None:
        if not self._rows:
            return
        if self.k0 and self._backfill_tries < BACKFILL_TRIES and not self._backfill():
            return  # the recorder has not written the first steps yet: next time
        geometry = None
        try:
            if self._live is None:
                from nodes.fatigue.worker import LiveFatigue

                self._live = LiveFatigue(self.cfg, [f"plant/arm/{f}" for f in self._fields],
                                         self.track_m)
                geometry = self._geometry()
            self._live.update(np.asarray(self._t), np.asarray(self._rows))
        except Exception as exc:  # a config the engine refuses: say so on the page
            self.problem = f"{type(exc).__name__}: {exc}"
            self.state.set_map(None, {"k": self.next_k - 1, "problem": self.problem})
            return
        self._t, self._rows = [], []
        res = self._live.result()
        D = np.asarray(res.damage, dtype=float)
        k = self.next_k - 1
        distance = self.track_m * (k + 1) / (self.n_steps + 1)
        dmax = float(D.max()) if D.size else 0.0
        with np.errstate(divide="ignore"):
            logd = np.where(D > 0, np.round(np.log10(np.maximum(D, 1e-300)), 3), np.nan)
        self.state.set_map(geometry, {
            "k": k, "from_k": self.k0, "missing_steps": self.gaps, "final": k >= self.n_steps,
            "from_journal": self.backfilled,
            "max_damage": dmax, "critical_node_id": int(res.critical_node_id),
            "distance_m": distance, "life_km": distance / dmax / 1000.0 if dmax > 0 else "inf",
            "log10_damage": [None if np.isnan(v) else float(v) for v in logd],
        })

    def _backfill(self) -> bool:
        """The steps before the scope joined, from the journal: True when in (or given up)."""
        from cosim.errors import WireError
        from cosim.journal import iter_records
        from cosim.wire import decode

        assert self.journal is not None, "backfill without a journal (its tries start used up)"
        self._backfill_tries += 1
        want = "/".join(ch.LOAD_CHANNEL)
        early: dict[int, tuple[float, list[float]]] = {}
        try:
            for channel, raw in iter_records(self.journal):  # a segment at a time (#32)
                if channel != want:
                    continue
                msg = decode(raw)
                if 0 <= msg.k < (self.k0 or 0):
                    early[msg.k] = (msg.t, [float(msg.d[f]) for f in self._fields])
        except (OSError, ValueError, KeyError, TypeError, WireError):
            pass
        if len(early) < (self.k0 or 0):
            return self._backfill_tries >= BACKFILL_TRIES
        self.backfilled = len(early)
        self._t[:0] = [early[k][0] for k in range(self.backfilled)]
        self._rows[:0] = [early[k][1] for k in range(self.backfilled)]
        self.k0 = 0
        self._backfill_tries = BACKFILL_TRIES
        return True

    def _geometry(self) -> dict[str, Any]:
        """Node positions and hardpoints [mm] in the arm frame (x forward, y outboard, z up)."""
        from cosim import lower_arm as geo

        inf = self._live.inf
        ids = [int(i) for i in inf.node_ids]
        xyz = getattr(inf, "node_xyz", None)
        if xyz is None:
            return {"node_id": ids, "xyz_mm": None, "hardpoints": {}}
        xyz = np.round(np.asarray(xyz, dtype=float) * 1e3, 2)
        return {"node_id": ids, "xyz_mm": xyz.tolist(),
                "hardpoints": {n: [round(float(v) * 1e3, 2) for v in p[:3]]
                               for n, p in geo.HARDPOINTS.items()}}
