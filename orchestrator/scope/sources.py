"""The scope's data: :class:`LiveSource` listens to a live run like ``suscosim tap`` (nothing
published); :class:`JournalSource` replays a finished run's journal without a bus, its coupling
residual computed again as the recorder did (:class:`ReplayResidual`). The damage map
(:class:`DamageMap`) is computed from the ``plant/arm`` loads with the live fatigue node's own
engine (:class:`nodes.fatigue.worker.LiveFatigue`), so its last step's largest damage is the
run's ``max_damage_per_pass``; a scope that joins late reads the missed steps from the journal.
Damage per node [-] (Miner, per pass so far, residue closed) sent as log10; positions [mm].
"""

from __future__ import annotations

import queue
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

from cosim import channels as ch
from cosim import keys
from cosim.errors import WireError
from cosim.step_message import expand
from cosim.wire import Message, decode

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
        from cosim.journal import iter_records

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


_CTL_STATES = {"ready": "ready", "waiting": "up", "progress": "stepping", "done": "done",
               "error": "error"}


class _Router:
    def __init__(self, state: ScopeState, damage: DamageMap | None) -> None:
        self.state, self.damage = state, damage

    def file(self, node: str, channel: str, msg: Message, now: float) -> None:
        st = self.state
        if channel == keys.CTL:
            state = _CTL_STATES.get(msg.kind)
            if state:
                info = str(msg.d.get("error") or msg.d.get("reason") or "") \
                    if msg.kind == "error" else ""
                st.node_event(node, state, msg.k if msg.k >= 0 else -1, msg.t, info, now)
            return
        if node == keys.ORCHESTRATOR and channel == keys.CLOCK:
            if msg.kind == "start" and "n_steps" in msg.d:
                st.run_event("stepping", n_steps=msg.d.get("n_steps"), h=msg.d.get("h"))
            elif msg.kind == "done":  # k = n_steps: for a scope that joined after the
                # start (a short run can end between two of its scenario queries)
                st.run_event("done", n_steps=msg.k if msg.k > 0 else None)
            elif msg.kind == "abort":
                st.run_event("failed", reason=str(msg.d.get("reason", "aborted")))
            return
        if msg.kind != "data":
            return
        if (node, channel) == (ch.FATIGUE, ch.DAMAGE):
            st.set_fatigue(msg.k, msg.t, msg.d)
            return
        if (node, channel) == ch.COUPLING_CHANNEL:
            st.set_coupling(msg.k, msg.t, msg.d)
            return
        if (node, channel) == ch.LOAD_CHANNEL and self.damage is not None:
            self.damage.push(msg, now)
        if st.selection.wants(node, channel):
            st.add_data(node, channel, msg, now)
        elif msg.k >= 0:
            st.node_event(node, "stepping", msg.k, msg.t, now=now)


class LiveSource:
    def __init__(self, bus: Any, state: ScopeState, damage: DamageMap | None = None) -> None:
        self.bus, self.state = bus, state
        self.router = _Router(state, damage)
        self.inbox: queue.SimpleQueue[tuple[str, bytes, float] | None] = queue.SimpleQueue()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, name="scope-source", daemon=True)

    def keyexprs(self) -> list[str]:
        """Every producer's ``step``, the selection's keys (a replay's), control (no ``**``)."""
        run = self.state.run_id
        exprs = [f"{keys.PREFIX}/{run}/*/{keys.STEP}"] + self.state.selection.keyexprs(run) + [
            f"{keys.PREFIX}/{run}/*/{keys.CTL}", keys.key(run, keys.ORCHESTRATOR, keys.CLOCK),
            keys.key(run, ch.FATIGUE, ch.DAMAGE), keys.key(run, *ch.COUPLING_CHANNEL)]
        if self.router.damage is not None:
            exprs.append(keys.key(run, *ch.LOAD_CHANNEL))
        return list(dict.fromkeys(exprs))

    def start(self) -> None:
        put, clock = self.inbox.put, time.monotonic
        self._thread.start()
        for kx in self.keyexprs():
            self.bus.subscribe(kx, lambda key, raw: put((key, raw, clock())))
        self.bus.watch(f"{keys.PREFIX}/{self.state.run_id}/*/{keys.ALIVE}", self._on_alive)

    def attach(self, damage: DamageMap) -> None:
        """Start the damage map once the scenario came (a scope started before its run)."""
        self.router.damage = damage
        put, clock = self.inbox.put, time.monotonic
        self.bus.subscribe(keys.key(self.state.run_id, *ch.LOAD_CHANNEL),
                           lambda key, raw: put((key, raw, clock())))

    def _on_alive(self, key: str, alive: bool) -> None:
        try:
            _run, node, _ch = keys.parse_key(key)
        except ValueError:
            return
        if node != keys.ORCHESTRATOR:
            self.state.node_event(node, "up" if alive else "gone")

    def _loop(self) -> None:
        while not self._stop.is_set():
            try:
                item = self.inbox.get(timeout=0.2)
            except queue.Empty:
                continue
            if item is None:
                break
            key, raw, now = item
            try:
                parts = expand(key, decode(raw))  # a step: its channels' messages
            except (ValueError, WireError):
                self.state.count_undecodable()
                continue
            for vkey, msg in parts:
                try:
                    _run, node, channel = keys.parse_key(vkey)
                    self.router.file(node, channel, msg, now)
                except Exception:  # a malformed field must not stop the scope
                    self.state.count_undecodable()
        if self.router.damage is not None:
            self.router.damage.flush()

    def close(self) -> None:
        self._stop.set()
        self.inbox.put(None)
        self._thread.join(timeout=5)


class ReplayResidual:
    """``recorder/coupling`` again from a journal's data messages, as the recorder does."""

    def __init__(self, channels: Any, run: dict[str, Any], state: ScopeState,
                 period_s: float = 0.1) -> None:
        from cosim.coupling_stream import LiveResidual
        from cosim.table_writer import TableWriter

        names = sorted(f"{n}/{c}" for n, c in channels)
        self.table = TableWriter(names, None)
        self.live = LiveResidual(None if run.get("adaptive") else float(run["h"]),
                                 run["coupling"], run["exchange"], names)
        self.state, self.period_s = state, period_s
        self._last = 0.0

    def data(self, name: str, msg: Message) -> None:
        rows = self.table.rows
        if self.table.add(name, msg.k, msg.t, msg.d) is not None:
            return  # not taken by the table: the recorder would not have journaled it
        self.live.add(name, msg.k, msg.t, msg.d)
        if self.table.rows > rows:
            self.live.row(msg.k)
        now = time.monotonic()
        if now - self._last >= self.period_s:
            self._last = now
            self.flush()

    def flush(self) -> None:
        for k, t, d in self.live.take():
            self.state.set_coupling(k, t, d)


class JournalSource:
    """Replay ``records`` at ``speed`` x the recorded pace (None: at once)."""

    def __init__(self, records: Any, state: ScopeState,
                 speed: float | None = 1.0, damage: DamageMap | None = None,
                 run: dict[str, Any] | None = None) -> None:
        self.records, self.state, self.speed = records, state, speed
        self.router = _Router(state, damage)
        self.residual: ReplayResidual | None = None
        channels = getattr(records, "channels", None)
        if run and channels and run.get("mode") != "reference":
            try:
                self.residual = ReplayResidual(channels, run, state)
            except (KeyError, ValueError, TypeError):  # an old scenario: no residual
                self.residual = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, name="scope-replay", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def _loop(self) -> None:
        st = self.state
        st.run_event("stepping")
        if not len(self.records):
            st.run_event("done")
            return
        t_first: float | None = None
        start = time.monotonic()
        for node, channel, raw, t in self.records:
            if self._stop.is_set():
                return
            if t_first is None:
                t_first = t
            if self.speed is not None:
                ahead = start + (t - t_first) / self.speed - time.monotonic()
                if ahead > 0.0005:
                    if self._stop.wait(ahead):
                        return
            try:
                msg = decode(raw)
            except WireError:
                st.count_undecodable()
                continue
            self.router.file(node, channel, msg, time.monotonic())
            if self.residual is not None and msg.kind == "data" and msg.k >= 0:
                self.residual.data(f"{node}/{channel}", msg)
        if self.router.damage is not None:
            self.router.damage.flush()
        if self.residual is not None:
            self.residual.flush()
        for node in st.nodes_known():
            st.node_event(node, "done", st.k, st.t)
        st.run_event("done")

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5)
