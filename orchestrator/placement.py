"""CPU placement of the local node processes (pure logic, plus one system call to apply it).

On a small machine the node processes of a run, their Zenoh threads and the orchestrator
share few cores. Left to the scheduler they migrate between cores at every wake-up of the
lock-step exchange; pinning each process to one core, with the two force nodes on different
cores (they compute at the same time, on the plant's state) and the plant on the
controller's core (the plant waits while they compute), gave about +40 % coupled steps/s in
the sequential exchange on the 2-core machine of docs/cosim.md (``bench/bench_throughput.py
--pin off`` against the default).

Layout by the number of usable cores n (``os.sched_getaffinity``), c0 < c1 < ... :

The layout is each kind's ``cores`` in the node registry (:mod:`cosim.node_kinds`):

==========  =====  =========  ==========  =========================================
n           plant  tyre_road  controller  recorder, fatigue (and any other node)
==========  =====  =========  ==========  =========================================
1           (no pinning)
2           c0     c1         c0          c1
3           c0     c1         c2          c0
>= 4        c0     c1         c2          c3
==========  =====  =========  ==========  =========================================

A pinned node also polls its input for a short while before it blocks (``--spin-us``, see
``Participant.spin_s``): its core then does not go idle between two steps.

A pinned node off the coupled chain's critical path (the recorder, the live fatigue node:
every kind but the coupled ones, :func:`cosim.node_kinds.off_critical_path`) runs in Linux's
``SCHED_IDLE`` class (:func:`place`): it gets the cores when the coupled nodes wait for each
other, and a coupled node that wakes takes its core back at once instead of waiting for the
recorder's or the fatigue node's work to yield. Both take their inputs as they come, in
arrears, so their results do not depend on when they run. Interleaved runs on the 2-core VM
(docs/cosim.md, "Background listeners"): the corner with live fatigue 1 494 -> 1 824 and the
lumped car 2 351 -> 2 904 coupled steps/s (medians of three), and the runs ended sooner too
(the listeners kept up). The price: on a machine where other programs keep every core busy a
``SCHED_IDLE`` listener gets almost nothing and can fall behind until the run stalls; such a
machine is what ``--pin off`` is for (nothing pinned, nothing in ``SCHED_IDLE``; the fatigue
node's own ``nice +10`` stays).

``auto`` pins on machines of 2 to ``AUTO_MAX_CORES`` usable cores, where the processes must
share cores anyway; on a bigger machine the scheduler keeps each process on a core of its own
and pinning every run to the same cores would only hurt runs side by side (a sweep with
several jobs starts its runs with ``--pin off``).
"""

from __future__ import annotations

import os
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


def background(pid: int) -> bool:
    """Put process ``pid`` in the ``SCHED_IDLE`` scheduling class (its threads started later
    inherit it); False where the OS has no such class or refuses."""
    try:
        os.sched_setscheduler(pid, os.SCHED_IDLE, os.sched_param(0))
        return True
    except (AttributeError, OSError):
        return False


def place(pid: int, name: str, core: int) -> tuple[bool, bool]:
    """Pin node process ``pid`` (node ``name``) to ``core`` and, if it is off the coupled
    chain's critical path, put it in ``SCHED_IDLE`` (see the module's docstring): (pinned,
    in the background). Call it before the process starts any thread."""
    if not pin(pid, core):
        return False, False
    return True, nk.off_critical_path(name) and background(pid)


def pin(pid: int, core: int) -> bool:
    """Pin process ``pid`` to ``core`` (its threads started later inherit it); False if the
    process is gone already or the OS refuses."""
    try:
        os.sched_setaffinity(pid, {core})
        return True
    except (AttributeError, OSError):
        return False
