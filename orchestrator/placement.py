"""CPU placement of the local node processes (pure logic, plus one system call to apply it).

Each process is pinned to one core (each kind's ``cores`` in :mod:`cosim.node_kinds`; c0 < c1
< ... are the usable cores, ``os.sched_getaffinity``): the two force nodes on different cores
(they compute at the same time), the plant on the controller's core (it waits while they
compute). ``python -m bench throughput --pin off`` measures the gain against the default.

==========  =====  =========  ==========  =========================================
n cores     plant  tyre_road  controller  recorder, fatigue (and any other node)
==========  =====  =========  ==========  =========================================
1           (no pinning)
2           c0     c1         c0          c1
3           c0     c1         c2          c0
>= 4        c0     c1         c2          c3
==========  =====  =========  ==========  =========================================

A pinned node polls its input before it blocks (``--spin-us``, :func:`spin_us`: the plant 1
ms, as long as a force round trip can take, a force node 600 us, one plant step; 200 us on a
core a sink shares, and for the sinks). Coupled nodes that
share a core (the plant and the controller on 2 cores) run in ``SCHED_BATCH``: a message that
wakes one does not preempt the other in the middle of its step (the controller woken by the
plant's state used to preempt the plant's put before it had reached the tyre/road node's
link); they hand the core over where the one running polls (``sched_yield``), and their Zenoh
threads run on the other core (:func:`zenoh_core`). Once the run has started every coupled
node's Zenoh threads run in real time (:data:`ZENOH_RT_PRIORITY`). A node off the
critical path (:func:`cosim.node_kinds.off_critical_path`) runs in ``SCHED_IDLE`` once the run
has started (its inputs are buffered: results do not depend on when it runs); a starved one
goes back to the normal class (:class:`BackgroundGuard`). ``auto`` pins on 2 to
``AUTO_MAX_CORES`` cores (on a bigger machine, runs side by side would share the same cores).
"""

from __future__ import annotations

import os
import time
from collections.abc import Iterable, Mapping

from cosim import node_kinds as nk

PIN_MODES = ("auto", "on", "off")
AUTO_MAX_CORES = 4


def usable_cores() -> list[int]:
    """The cores this process may run on (empty where the OS cannot tell, e.g. macOS)."""
    try:
        return sorted(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return []


def core_layout(nodes: Iterable[str], cores: list[int]) -> dict[str, int]:
    """The core of each node (the table above); empty with fewer than 2 cores."""
    n = len(cores)
    return {} if n < 2 else {node: cores[nk.core_index(node, n)] for node in nodes}


def should_pin(mode: str, cores: list[int]) -> bool:
    if mode not in PIN_MODES:
        raise ValueError(f"pin mode must be one of {', '.join(PIN_MODES)}, got {mode!r}")
    if mode == "off" or len(cores) < 2:
        return False
    return mode == "on" or len(cores) <= AUTO_MAX_CORES


def sharing_a_core(layout: Mapping[str, int]) -> list[str]:
    """The coupled nodes of ``layout`` (node -> core) whose core holds another coupled node."""
    chain = [n for n in layout if not nk.off_critical_path(n)]
    return [n for n in chain if sum(layout[m] == layout[n] for m in chain) > 1]


def spin_us(name: str, layout: Mapping[str, int]) -> int:
    """How long pinned node ``name`` polls its input before it blocks [us]: its kind's
    ``spin_us``, at most :data:`cosim.node_kinds.NodeKind.spin_us` on a core it shares with a
    node off the critical path (polling longer would starve it: 3 cores put the sinks on
    the plant's). Blocking at once there instead was better only while Zenoh's threads ran
    in the normal class (#41: then lumped -13 %, corner + live fatigue -3 %)."""
    core = layout.get(name)
    shared = any(layout[n] == core for n in layout if n != name and nk.off_critical_path(n))
    return min(nk.spin_us(name), nk.NodeKind.spin_us) if shared else nk.spin_us(name)


ZENOH_THREADS = ("net-", "app-", "tx-", "rx-", "acc-")
"""The name prefixes of Zenoh's runtime threads (its network, application, transmit, receive
and accept runtimes' workers and their blocking pools)."""


def zenoh_core(name: str, layout: Mapping[str, int]) -> int:
    """The core for the Zenoh threads of pinned node ``name``: its own, but the first other
    one for a coupled node sharing its core with another (the plant and the controller on 2
    cores): a socket thread woken on the shared core preempted the plant mid-put, before the
    state had reached the tyre/road node (a traced Ch 6 run: 0-95 % of the puts, by run)."""
    others = [c for c in sorted(set(layout.values())) if c != layout[name]]
    return others[0] if name in sharing_a_core(layout) and others else layout[name]


ZENOH_RT_PRIORITY = 1
"""``SCHED_FIFO`` priority of the coupled nodes' Zenoh threads once a run has started: woken
by a message they preempt what their core runs and hand the message over in ~10 us; in the
normal class the controller's state, its threads moved to the tyre/road node's core
(:func:`zenoh_core`), waited in its socket behind that node's whole step (in alternating runs
corner + live fatigue +18 %, lumped +8 %, 7-DOF +6 %; the tyre/road node's own, lumped +4 %).
They only read sockets; the kernel's real-time throttling leaves others 5 % in any case, and
Zenoh puts its own shared-memory watchdogs in ``SCHED_FIFO`` likewise."""


def move_zenoh_threads(pid: int, core: int) -> bool:
    """Pin the Zenoh threads of ``pid`` (:data:`ZENOH_THREADS`, once its session is open; the
    threads they start inherit it) to ``core`` in ``SCHED_FIFO`` at :data:`ZENOH_RT_PRIORITY`
    (in the normal class where that is not permitted); False if refused or none."""
    moved = False
    try:
        for tid in _threads(pid):
            try:
                with open(f"/proc/{pid}/task/{tid}/comm") as f:
                    if not f.read().startswith(ZENOH_THREADS):
                        continue
                os.sched_setaffinity(tid, {core})
                try:
                    os.sched_setscheduler(tid, os.SCHED_FIFO, os.sched_param(ZENOH_RT_PRIORITY))
                except PermissionError:  # not root (no CAP_SYS_NICE)
                    os.sched_setscheduler(tid, os.SCHED_OTHER, os.sched_param(0))
                moved = True
            except (ProcessLookupError, FileNotFoundError):  # a thread that ended meanwhile
                continue
    except (AttributeError, OSError):
        return False
    return moved


def batch(pid: int) -> bool:
    """``pid`` (before it has started a thread: they inherit it) to ``SCHED_BATCH``: its
    wake-ups do not preempt the task running on its core (see the module's docstring)."""
    try:
        os.sched_setscheduler(pid, os.SCHED_BATCH, os.sched_param(0))
        return True
    except (AttributeError, OSError):
        return False


def _threads(pid: int) -> list[int]:
    return [int(t) for t in os.listdir(f"/proc/{pid}/task")]


def _set_class(pid: int, from_policy: int | None, to_policy: int) -> bool:
    """Every thread of ``pid`` in ``from_policy`` (None: not real-time) to ``to_policy``."""
    try:
        for tid in _threads(pid):
            try:
                now = os.sched_getscheduler(tid)
                if now == to_policy or (from_policy is not None and now != from_policy) \
                        or now in (os.SCHED_FIFO, os.SCHED_RR):  # Zenoh's shm watchdogs
                    continue
                os.sched_setscheduler(tid, to_policy, os.sched_param(0))
            except ProcessLookupError:  # a thread that ended meanwhile
                continue
        return True
    except (AttributeError, OSError, ValueError):
        return False


def background(pid: int) -> bool:
    """Every thread of ``pid`` to ``SCHED_IDLE`` (once the run has started, not before)."""
    return _set_class(pid, None, os.SCHED_IDLE) if hasattr(os, "SCHED_IDLE") else False


def foreground(pid: int) -> bool:
    """Every ``SCHED_IDLE`` thread of ``pid`` back to the normal class."""
    if not hasattr(os, "SCHED_IDLE"):
        return False
    return _set_class(pid, os.SCHED_IDLE, os.SCHED_OTHER)


STARVED_WINDOW_S = 2.0  # [s] over which a background node's run-queue wait is measured
STARVED_FRACTION = 0.9  # a thread runnable but waiting more than this share of it is starved
# (0.5 moved the Ch 6 fatigue node back, behind but not starved; then it held the tyre's core)


def run_queue_waits_s(pid: int) -> dict[int, float]:
    """[s] each thread of ``pid`` waited runnable on a run queue (schedstat field 2)."""
    out: dict[int, float] = {}
    try:
        tids = _threads(pid)
    except OSError:
        return out
    for tid in tids:
        try:
            with open(f"/proc/{pid}/task/{tid}/schedstat") as f:
                out[tid] = int(f.read().split()[1]) * 1e-9
        except (OSError, IndexError, ValueError):
            continue
    return out


def starved(waited_s: float, over_s: float, fraction: float = STARVED_FRACTION) -> bool:
    return over_s > 0 and waited_s > fraction * over_s


class BackgroundGuard:
    """Moves a starved ``SCHED_IDLE`` node back to the normal class for the rest of the run."""

    def __init__(self, window_s: float = STARVED_WINDOW_S) -> None:
        self.window_s = window_s
        self._since: dict[int, tuple[float, dict[int, float]]] = {}  # pid -> (t, waits)
        self.moved: list[str] = []  # the nodes moved back, in order

    def check(self, pids: dict[str, int]) -> list[str]:
        """Measure the background nodes ``{name: pid}``; the names moved back now."""
        now, moved = time.monotonic(), []
        for name, pid in pids.items():
            if name in self.moved or not (waits := run_queue_waits_s(pid)):
                continue
            t0, w0 = self._since.setdefault(pid, (now, waits))
            if now - t0 < self.window_s:
                continue
            self._since[pid] = (now, waits)
            worst = max((w - w0[tid] for tid, w in waits.items() if tid in w0), default=0.0)
            if starved(worst, now - t0) and foreground(pid):
                self.moved.append(name)
                moved.append(name)
        return moved


def pin(pid: int, core: int) -> bool:
    """Pin ``pid`` to ``core`` (later threads inherit it); False if refused."""
    try:
        os.sched_setaffinity(pid, {core})
        return True
    except (AttributeError, OSError):
        return False
