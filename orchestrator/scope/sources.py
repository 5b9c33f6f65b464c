"""The scope's data: :class:`LiveSource` listens to a live run like ``suscosim tap`` (nothing
published); :class:`JournalSource` replays a finished run's journal without a bus, its coupling
residual computed again as the recorder did (:class:`ReplayResidual`).
"""

from __future__ import annotations

import queue
import threading
import time
from typing import Any

from cosim import channels as ch
from cosim import keys
from cosim.errors import WireError
from cosim.step_message import expand
from cosim.wire import Message, decode

from .damage import DamageMap
from .state import ScopeState

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
    """Subscribe to a live run on ``bus`` (the bus owns the subscribers)."""

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
