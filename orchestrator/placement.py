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

A pinned node polls its input briefly before it blocks (``--spin-us``, ``Participant.spin_s``).
A node off the coupled chain's critical path (:func:`cosim.node_kinds.off_critical_path`) runs
in ``SCHED_IDLE`` once the run has started (:func:`background`); it takes its inputs in
arrears, so its results do not depend on when it runs. A starved one goes back to the normal
class for the rest of the run (:class:`BackgroundGuard`, summary.json ``background_starved``);
``--pin off`` keeps everything in the normal class. ``auto`` pins on 2 to ``AUTO_MAX_CORES``
usable cores; on a bigger machine pinning every run to the same cores would only hurt runs
side by side.
"""

from __future__ import annotations

import os
import time
from collections.abc import Iterable

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
    """The core of each node (see the table above: each kind's ``cores`` in the registry,
    :mod:`cosim.node_kinds`; a name that is no kind is placed as the listeners are); empty
    with fewer than 2 cores."""
    n = len(cores)
    if n < 2:
        return {}
    return {node: cores[nk.core_index(node, n)] for node in nodes}


def should_pin(mode: str, cores: list[int]) -> bool:
    """Whether to pin, for ``mode`` in :data:`PIN_MODES` and the usable ``cores``."""
    if mode not in PIN_MODES:
        raise ValueError(f"pin mode must be one of {', '.join(PIN_MODES)}, got {mode!r}")
    if mode == "off" or len(cores) < 2:
        return False
    return mode == "on" or len(cores) <= AUTO_MAX_CORES


def _threads(pid: int) -> list[int]:
    """The thread ids of process ``pid`` (OSError if it is gone)."""
    return [int(t) for t in os.listdir(f"/proc/{pid}/task")]


def _set_class(pid: int, from_policy: int | None, to_policy: int) -> bool:
    """Every thread of ``pid`` (in ``from_policy``; None: any but real-time) to ``to_policy``;
    False if the process is gone, the OS refuses or has no such class."""
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
    """Put every thread of process ``pid`` in the ``SCHED_IDLE`` class (later threads inherit
    it); False where the OS has no such class or refuses. Called once the run has started: at
    start-up an idle-class node could wait for its core longer than the start timeout."""
    return _set_class(pid, None, os.SCHED_IDLE) if hasattr(os, "SCHED_IDLE") else False


def foreground(pid: int) -> bool:
    """Move every ``SCHED_IDLE`` thread of process ``pid`` back to the normal class (its
    nice value is kept); False if the process is gone or the OS refuses."""
    if not hasattr(os, "SCHED_IDLE"):
        return False
    return _set_class(pid, os.SCHED_IDLE, os.SCHED_OTHER)


STARVED_WINDOW_S = 2.0
"""How long [s] a background node's waiting is measured over (:class:`BackgroundGuard`)."""
STARVED_FRACTION = 0.5
"""A background node one of whose threads waited on its core's run queue for more than this
fraction of :data:`STARVED_WINDOW_S` is starved: it had work and did not get the core."""


def run_queue_waits_s(pid: int) -> dict[int, float]:
    """How long [s] each thread of process ``pid`` has waited on a run queue, runnable but
    not running (``/proc/PID/task/TID/schedstat``, second field); empty if it is gone."""
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
    """Whether a thread that waited ``waited_s`` on a run queue during ``over_s`` of wall
    time is starved (it waited more than ``fraction`` of it)."""
    return over_s > 0 and waited_s > fraction * over_s


class BackgroundGuard:
    """Moves a starved ``SCHED_IDLE`` node (:func:`starved` over :data:`STARVED_WINDOW_S`) back
    to the normal class for the rest of the run; :meth:`check` on every tick of the clock."""

    def __init__(self, window_s: float = STARVED_WINDOW_S) -> None:
        self.window_s = window_s
        self._since: dict[int, tuple[float, dict[int, float]]] = {}  # pid -> (t, waits)
        self.moved: list[str] = []
        """The nodes moved back to the normal class, in order."""

    def check(self, pids: dict[str, int]) -> list[str]:
        """Measure the background nodes ``{name: pid}``; the names moved back this call."""
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
    """Pin process ``pid`` to ``core`` (its threads started later inherit it); False if the
    process is gone already or the OS refuses."""
    try:
        os.sched_setaffinity(pid, {core})
        return True
    except (AttributeError, OSError):
        return False
