"""CPU placement of the local node processes (orchestrator.placement)."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cosim import channels as ch
from cosim.node_kinds import off_critical_path
from orchestrator.placement import (
    AUTO_MAX_CORES,
    BackgroundGuard,
    background,
    core_layout,
    foreground,
    sharing_a_core,
    should_pin,
    spin_us,
    starved,
    zenoh_core,
)

NODES = [*ch.NODES, ch.FATIGUE]


def test_two_cores_split_the_force_nodes_and_put_the_plant_with_the_controller() -> None:
    lay = core_layout(NODES, [4, 7])
    assert lay == {"plant": 4, "controller": 4, "tyre_road": 7, "recorder": 7, "fatigue": 7}


@pytest.mark.parametrize("cores", [[4, 7], [0, 1, 2], [0, 1, 2, 3]])
def test_batch_for_coupled_nodes_sharing_a_core_and_the_plant_polls_longest_alone(
        cores: list[int]) -> None:
    """2 cores: the plant and the controller share one (SCHED_BATCH); the plant polls 1 ms
    for its forces, a force node 600 us, but a node on a core a sink shares (the tyre/road
    node on 2 cores, the plant on 3) and the sinks only 200 us."""
    lay = core_layout(NODES, cores)
    assert sharing_a_core(lay) == (["plant", "controller"] if len(cores) == 2 else [])
    own = {"plant": 1000, "tyre_road": 600, "controller": 600, "recorder": 200, "fatigue": 200}
    for node in NODES:
        with_sink = any(lay[n] == lay[node] for n in ("recorder", "fatigue") if n != node)
        assert spin_us(node, lay) == (200 if with_sink else own[node]), node
    assert lay["recorder"] == lay[{2: "tyre_road", 3: "plant"}.get(len(cores), "recorder")]


@pytest.mark.parametrize("cores", [[4, 7], [0, 1, 2], [0, 1, 2, 3]])
def test_the_zenoh_threads_of_nodes_sharing_a_core_go_to_the_other(cores: list[int]) -> None:
    """2 cores: the plant's and the controller's Zenoh threads on the tyre/road node's core;
    from 3 cores no coupled node shares one, and every node's threads stay with it."""
    lay = core_layout(NODES, cores)
    want = {"plant": 7, "controller": 7} if len(cores) == 2 else {}
    assert {n: c for n in NODES if (c := zenoh_core(n, lay)) != lay[n]} == want


@pytest.mark.parametrize("cores", [[0, 1, 2], [0, 1, 2, 3], list(range(16))])
def test_from_three_cores_each_coupled_node_has_its_own(cores: list[int]) -> None:
    lay = core_layout(NODES, cores)
    assert len({lay["plant"], lay["tyre_road"], lay["controller"]}) == 3
    assert set(lay.values()) <= set(cores)
    if len(cores) >= 4:  # the listeners keep off the coupled nodes' cores
        assert lay["recorder"] == lay["fatigue"] == cores[3]


def test_no_layout_on_one_core_and_unknown_nodes_go_with_the_listeners() -> None:
    assert core_layout(NODES, [0]) == {} and core_layout(NODES, []) == {}
    assert core_layout(["plant", "probe"], [0, 1])["probe"] == 1


def test_auto_pins_only_small_machines() -> None:
    assert should_pin("auto", [0, 1]) and should_pin("auto", list(range(AUTO_MAX_CORES)))
    assert not should_pin("auto", list(range(AUTO_MAX_CORES + 1)))
    assert should_pin("on", list(range(32))) and not should_pin("on", [0])
    assert not should_pin("off", [0, 1])
    with pytest.raises(ValueError, match="auto, on, off"):
        should_pin("sometimes", [0, 1])


def test_background_puts_every_thread_in_sched_idle_and_foreground_takes_it_back() -> None:
    """A real child process with threads: :func:`background` puts every one of them in
    SCHED_IDLE, :func:`foreground` every one back in the normal class."""
    child = subprocess.Popen([sys.executable, "-c", (
        "import threading, time\n"
        "for _ in range(3): threading.Thread(target=time.sleep, args=(30,), daemon=True).start()\n"
        "print('up', flush=True); time.sleep(30)")], stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout is not None and child.stdout.readline() == "up\n"
        tids = [int(t) for t in os.listdir(f"/proc/{child.pid}/task")]
        assert len(tids) == 4
        assert background(child.pid)
        assert {os.sched_getscheduler(t) for t in tids} == {os.SCHED_IDLE}
        assert foreground(child.pid)
        assert {os.sched_getscheduler(t) for t in tids} == {os.SCHED_OTHER}
    finally:
        child.kill()
        child.wait()


def test_only_nodes_that_are_no_coupled_kind_are_off_the_critical_path() -> None:
    assert [n for n in (*NODES, "probe") if off_critical_path(n)] == \
        ["recorder", "fatigue", "probe"]


def test_starved_is_waiting_on_the_run_queue_for_more_than_nine_tenths_of_the_window() -> None:
    """A sink the coupled chain keeps waiting half the time is behind, not starved: its lag is
    bounded by the sink window (#41); one that other programs starve waits nearly always."""
    assert starved(1.85, 2.0) and not starved(1.75, 2.0) and not starved(1.1, 2.0)
    assert not starved(0.0, 0.0) and starved(0.3, 1.0, fraction=0.2)


def _busy(core: int) -> subprocess.Popen:
    child = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    os.sched_setaffinity(child.pid, {core})
    return child


def test_a_starved_background_node_goes_back_to_the_normal_class_and_a_fed_one_stays() -> None:
    """Real processes on one core: a busy loop in SCHED_IDLE next to a busy loop in the
    normal class waits on the run queue nearly all the time: the guard moves it back to the
    normal class (every thread). A SCHED_IDLE process that sleeps, on the same core, stays."""
    core = sorted(os.sched_getaffinity(0))[-1]
    hog, idle_busy = _busy(core), _busy(core)
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; print('up', flush=True); "
                                "time.sleep(60)"], stdout=subprocess.PIPE, text=True)
    try:
        assert sleeper.stdout is not None and sleeper.stdout.readline() == "up\n"
        while Path(f"/proc/{sleeper.pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "S":
            time.sleep(0.01)  # in its sleep before it shares the busy core: it needs no CPU
        assert background(idle_busy.pid) and background(sleeper.pid)
        os.sched_setaffinity(sleeper.pid, {core})
        guard = BackgroundGuard(window_s=0.5)
        pids = {"recorder": idle_busy.pid, "fatigue": sleeper.pid}
        deadline = time.monotonic() + 30  # a bound on a hang, not a timing assertion
        while not guard.moved and time.monotonic() < deadline:
            guard.check(pids)
            time.sleep(0.1)
        assert guard.moved == ["recorder"]
        assert os.sched_getscheduler(idle_busy.pid) == os.SCHED_OTHER
        assert os.sched_getscheduler(sleeper.pid) == os.SCHED_IDLE
    finally:
        for p in (hog, idle_busy, sleeper):
            p.kill()
            p.wait()
