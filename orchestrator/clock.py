"""The clock: serves the resolved scenario, publishes ``start`` once every node is present
(liveliness token) and ready, follows each node's step (the step barrier is in the nodes,
cosim.participant), ends the run when all are done, aborts it naming the node on an error, a
lost token or a stall. Signed with the run's key (:class:`cosim.auth.RunKey`); a node's control
message counts only when signed, well formed and plausible, else it is ``rejected``.
"""

from __future__ import annotations

import queue
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cosim import channels as ch
from cosim import keys
from cosim.auth import SESSION_FIELD, RunKey
from cosim.bus import Bus
from cosim.checkpoint import CheckpointError, checkpoint_key, prune_checkpoints, write_manifest
from cosim.control import check_node_control
from cosim.errors import RunError, ScenarioError, WireError
from cosim.run_checkpoint import NodeCheckpoints
from cosim.wire import decode, encode

START_PERIOD_S = 0.05
LIVELINESS_GRACE_S = 1.0
"""How long [s] a dropped liveliness token stays dropped before the node counts as dead (Zenoh
re-declares tokens while links reorganise under load; a local process's exit is seen at once)."""


@dataclass
class NodeStatus:
    alive: bool = False
    ready: bool = False
    started: bool = False
    done: bool = False
    done_at: float | None = None  # time.monotonic() when its "done" came
    k: int = -1
    last_seen: float = 0.0
    rejected: int = 0
    info: dict[str, Any] = field(default_factory=dict)
    result: dict[str, Any] = field(default_factory=dict)
    gone_since: float | None = None
    waiting_for: list[str] = field(default_factory=list)  # inputs not heard yet (start barrier)
    max_lag: int = 0  # a sink's largest lag behind the coupled chain [steps]


@dataclass
class ClockResult:
    nodes: dict[str, NodeStatus]
    wall_s: float  # [s] clock start to the end
    run_wall_s: float  # [s] ``start`` until every node is done (table export included)
    step_wall_s: float  # [s] ``start`` until the coupled chain's last step (steps_per_s)
    rejected: int = 0  # control messages rejected


class Clock:
    """Supervise one run on a bus (Zenoh or in-memory)."""

    def __init__(self, bus: Bus, run: str, nodes: list[str], scenario: dict[str, Any],
                 on_progress: Callable[[int, int], None] | None = None,
                 check_processes: Callable[[], str | None] | None = None,
                 auth: RunKey | None = None, on_started: Callable[[], None] | None = None) -> None:
        self.bus, self.run_id, self.scenario, self.auth = bus, run, scenario, auth
        self.status = {n: NodeStatus() for n in nodes}
        self.n_steps = int(scenario["run"]["n_steps"])  # adaptive step: the bound t_end / h_min
        self._adaptive = bool(scenario["run"].get("adaptive"))
        self.on_progress = on_progress or (lambda k, n: None)
        self.check_processes = check_processes or (lambda: None)
        self.on_started = on_started or (lambda: None)  # once every node has the start
        self.events: queue.SimpleQueue[tuple[str, str, Any]] = queue.SimpleQueue()
        self.rejected = 0
        plan = NodeCheckpoints.of(scenario, keys.ORCHESTRATOR) if "dir" in scenario["run"] else None
        self._ckpt_due = plan.due if plan is not None else frozenset()
        self._ckpt_entries: dict[int, dict[str, dict[str, Any]]] = {}
        self.checkpoints: list[int] = []  # the checkpoints completed (manifest written)
        clock_key = keys.key(run, keys.ORCHESTRATOR, keys.CLOCK)
        pub = bus.publisher(clock_key)
        sign = auth.signer(clock_key) if auth else (lambda raw: raw)
        self._sent: set[bytes] = set()  # the aborts this clock signed (a handful)
        self.foreign_abort: str | None = None  # a signed abort this clock did not send

        def clock_pub(raw: bytes) -> None:
            signed = sign(raw)
            if raw[:40].find(b"abort") >= 0 and len(self._sent) < 64:
                self._sent.add(signed)
            pub(signed)

        self._clock = clock_pub
        bus.subscribe(clock_key, self._on_clock)
        # the served scenario announces the run instance's nonce (cosim.auth): signed with
        # the key alone, as the nodes that fetch it do not know the nonce yet
        served = {**scenario, SESSION_FIELD: auth.nonce.hex()} if auth and auth.nonce else scenario
        blob = encode("start", -1, 0.0, served)  # raises on a number msgpack cannot hold
        scenario_key = keys.key(run, keys.ORCHESTRATOR, keys.SCENARIO)
        if auth:
            blob = auth.unbound().sign(scenario_key, blob)
        # the nodes watch this token: a killed orchestrator ends its nodes too
        self._token = bus.token(keys.key(run, keys.ORCHESTRATOR, keys.ALIVE))
        bus.serve(scenario_key, lambda: blob)
        bus.subscribe(keys.key(run, "*", keys.CTL), lambda k, raw: self.events.put(("ctl", k, raw)))
        bus.watch(keys.key(run, "*", keys.ALIVE),
                  lambda k, alive: self.events.put(("alive", k, alive)))

    def _on_clock(self, key: str, raw: bytes) -> None:
        """A message on the clock's key (bus thread): notes a :attr:`foreign_abort`."""
        if raw in self._sent or self.foreign_abort is not None:
            return
        try:
            msg = decode(self.auth.verify(key, raw) if self.auth else raw)
        except WireError:
            return  # the nodes reject it too
        if msg.kind == "abort":
            reason = str(msg.d.get("reason", "?"))[:200]
            self.foreign_abort = (f"the run was aborted by an abort this orchestrator did not "
                                  f"send (signed with the run's key: an insider; its reason: "
                                  f"{reason!r})")

    def _node_of(self, key: str) -> str | None:
        try:
            _, node, _ = keys.parse_key(key)
        except ValueError:
            return None
        return node if node in self.status else None

    def _pump(self, timeout: float) -> None:
        end = time.monotonic() + timeout
        while True:
            try:
                what, key, payload = self.events.get(timeout=max(0.0, end - time.monotonic()))
            except queue.Empty:
                return
            node = self._node_of(key)
            if node is None:
                continue
            st = self.status[node]
            now = time.monotonic()
            if what == "alive":
                st.alive = bool(payload)
                if payload:  # a token that drops (a paused process's lease) is no sign of life
                    st.last_seen = now
                st.gone_since = None if payload else (st.gone_since or now)
                continue
            try:
                msg = decode(self.auth.verify(key, payload) if self.auth else payload)
                check_node_control(msg.kind, msg.d)
                if msg.k > self.n_steps or (msg.kind == "done" and msg.k != self.n_steps
                                            and not self._adaptive):
                    raise WireError(f"implausible {msg.kind} at step {msg.k} of {self.n_steps}")
                if msg.kind == "checkpoint" and (msg.k not in self._ckpt_due
                                                 or msg.d["file"] != f"{node}.ckpt"):
                    raise WireError(f"implausible checkpoint {msg.d['file']!r} at step {msg.k}")
            except WireError as exc:
                self.rejected += 1
                if self.rejected <= 10 or self.rejected % 1000 == 0:
                    print(f"suscosim: rejected control message #{self.rejected} on {key}: "
                          f"{exc}", file=sys.stderr)
                continue
            if msg.kind != "waiting" or not st.started:  # waiting on an input is no progress
                st.last_seen = now
            st.rejected = msg.d.get("rejected", st.rejected)
            if msg.kind == "ready":
                st.ready, st.info, st.waiting_for = True, dict(msg.d.get("info", {})), []
            elif msg.kind == "waiting":
                st.waiting_for = [str(x) for x in msg.d.get("missing", [])][:8]
            elif msg.kind == "progress":
                st.started = st.started or st.ready
                if msg.k > st.k:
                    st.waiting_for = []
                st.k = max(st.k, msg.k)
            elif msg.kind == "done":
                st.done, st.k, st.result = True, msg.k, dict(msg.d)
                st.done_at = st.done_at or now
            elif msg.kind == "checkpoint":
                self._checkpointed(node, msg.k, msg.d)
            elif msg.kind == "error":
                code = msg.d.get("exit_code", 1)
                late = [n for n in msg.d.get("late", []) if n in self.status and n != node]
                if late:  # the node that noticed a silent producer: blame the producer
                    self.abort(self._blame_late(node, late, msg.d.get("message", "")))
                err: RunError | ScenarioError = RunError(f"node '{node}': {msg.d.get('message')}")
                if code == 2:
                    err.exit_code = 2
                self.abort(str(err), err)
            if now - self._last_tick > 0.1:
                self._tick()
            if time.monotonic() >= end:
                return

    def _checkpointed(self, node: str, k: int, entry: dict[str, Any]) -> None:
        """A node wrote its state at ``k``: once all have, the manifest completes it."""
        got = self._ckpt_entries.setdefault(k, {})
        got[node] = {f: entry[f] for f in ("file", "sha256", "bytes")}
        if len(got) < len(self.status):
            return
        del self._ckpt_entries[k]
        try:
            run = self.scenario["run"]
            write_manifest(Path(run["dir"]), k, k * float(run["h"]), self.scenario, got,
                           checkpoint_key(self.auth.key if self.auth else None))
        except (OSError, CheckpointError) as exc:
            print(f"suscosim: warning: checkpoint k={k} not completed: {exc}", file=sys.stderr)
            return
        self.checkpoints.append(k)
        keep = int(self.scenario["run"].get("checkpoint_keep", 0) or 0)
        if keep:
            prune_checkpoints(Path(run["dir"]), keep)

    def _tick(self) -> None:
        now = self._last_tick = time.monotonic()
        if self.foreign_abort is not None:
            raise RunError(self.foreign_abort)  # every node has it already
        dead = self.check_processes()
        if dead:
            if self.foreign_abort is not None:  # a node that obeyed it exited meanwhile
                raise RunError(self.foreign_abort)
            self.abort(dead)
        for node, st in self.status.items():
            if st.gone_since is not None and not st.done \
                    and now - st.gone_since > LIVELINESS_GRACE_S:
                self.abort(f"node '{node}' is gone (its liveliness token dropped: the "
                           f"process died or the network to it failed) at step {st.k}")
        ks = [st.k for st in self.status.values()]
        chain = max((st.k for n, st in self.status.items() if n in ch.COUPLED), default=-1)
        for node, st in self.status.items():
            if node not in ch.COUPLED and st.started and not st.done:
                st.max_lag = max(st.max_lag, chain - st.k)
        self.on_progress(min(ks), self.n_steps)

    def abort(self, reason: str, err: Exception | None = None) -> None:
        """Tell every node to stop, then raise (the error names the node)."""
        self.announce_abort(reason)
        raise err if err is not None else RunError(reason)

    def _blame(self, stale: list[tuple[int, str]], stall: float) -> str:
        """The stall's error naming, of the stale nodes, one others wait for that waits for
        nobody; else one others wait for; else a coupled node; else the furthest behind."""
        waiters: dict[str, list[str]] = {}
        for name, st in self.status.items():
            if st.done:
                continue
            for inp in st.waiting_for:
                waiters.setdefault(inp.partition("/")[0], []).append(f"{name} ({inp})")
        # the node others wait for may pass the stall a moment after one of them (its last
        # progress was later): it is a candidate as soon as it has been quiet over half the stall
        now = time.monotonic()
        quiet = [(st.k, n) for n, st in self.status.items()
                 if n in waiters and not st.done and (st.k, n) not in stale
                 and now - st.last_seen > stall / 2]
        tiers = ([(k, n) for k, n in stale + quiet
                  if n in waiters and not self.status[n].waiting_for],
                 [(k, n) for k, n in stale if n in waiters],
                 [(k, n) for k, n in stale if n in ch.COUPLED], stale)
        k, node = min(next(t for t in tiers if t))
        text = (f"node '{node}' made no progress for {stall:.1f} s (stalled at step {k} of "
                f"{self.n_steps})")
        if waiters.get(node):
            text += "; waiting for it: " + ", ".join(waiters[node])
        return text

    def _blame_late(self, noticed_by: str, late: list[str], message: str) -> str:
        """The error when ``noticed_by`` gave up waiting for ``late``: they are blamed."""
        stall = self.scenario["run"]["stall_timeout_s"]
        k, node = min((self.status[n].k, n) for n in late)
        return (f"node '{node}' made no progress for {stall:.1f} s (stalled at step {k} of "
                f"{self.n_steps}); waiting for it: {noticed_by} ({message})")

    def _why_not_ready(self, node: str) -> str:
        st = self.status[node]
        if not st.alive:
            return " (absent)"
        return f" (never heard {', '.join(st.waiting_for)})" if st.waiting_for else ""

    def announce_abort(self, reason: str) -> None:
        """Publish ``abort`` (the nodes stop, the recorder exports what it has)."""
        for _ in range(3):
            self._clock(encode("abort", -1, 0.0, {"reason": reason}))

    def run(self) -> ClockResult:
        t0 = time.monotonic()
        self._last_tick = t0
        cfg = self.scenario["run"]
        deadline = t0 + cfg["start_timeout_s"]
        while not all(st.ready for st in self.status.values()):
            if time.monotonic() > deadline:
                missing = [n for n, st in self.status.items() if not st.ready]
                self.abort(f"not ready within {cfg['start_timeout_s']:.0f} s: "
                           + ", ".join(f"'{n}'" + self._why_not_ready(n) for n in missing))
            self._pump(0.05)
            self._tick()
        info = {n: st.info for n, st in self.status.items()}
        start = encode("start", -1, 0.0, {"n_steps": self.n_steps, "h": cfg["h"], "info": info})
        t_run = time.monotonic()
        while not all(st.started or st.done for st in self.status.values()):
            self._clock(start)
            self._pump(START_PERIOD_S)
            if time.monotonic() - t_run > cfg["start_timeout_s"]:
                self.abort("nodes did not start: " + ", ".join(
                    n for n, st in self.status.items() if not st.started))
        self.on_started()
        stall = cfg["stall_timeout_s"]
        while not all(st.done for st in self.status.values()):
            self._pump(0.1)
            self._tick()
            now = time.monotonic()
            stale = [(st.k, node) for node, st in self.status.items()
                     if not st.done and now - st.last_seen > stall]
            if stale:
                self.abort(self._blame(stale, stall))
        run_wall = time.monotonic() - t_run
        for _ in range(3):
            self._clock(encode("done", self.n_steps, self.n_steps * cfg["h"], {}))
        coupled = [st.done_at for n, st in self.status.items()
                   if n in ch.COUPLED and st.done_at is not None]
        step_wall = max(coupled) - t_run if coupled else run_wall
        return ClockResult(self.status, time.monotonic() - t0, run_wall, step_wall, self.rejected)
