"""CPU placement of the local node processes (orchestrator.placement)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from cosim import channels as ch
from orchestrator.placement import AUTO_MAX_CORES, core_layout, place, should_pin

NODES = [*ch.NODES, ch.FATIGUE]


def test_two_cores_split_the_force_nodes_and_put_the_plant_with_the_controller() -> None:
    lay = core_layout(NODES, [4, 7])
    assert lay == {"plant": 4, "controller": 4, "tyre_road": 7, "recorder": 7, "fatigue": 7}


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


@pytest.mark.parametrize(("name", "idle"), [("plant", False), ("tyre_road", False),
                                            ("controller", False), ("recorder", True),
                                            ("fatigue", True), ("probe", True)])
def test_place_pins_and_puts_only_nodes_off_the_critical_path_in_sched_idle(
        name: str, idle: bool) -> None:
    """A real child process: pinned to the core, and in SCHED_IDLE exactly when the node is
    no coupled kind (the recorder, the fatigue node, a name that is no kind)."""
    core = sorted(os.sched_getaffinity(0))[-1]
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        assert place(child.pid, name, core) == (True, idle)
        assert os.sched_getaffinity(child.pid) == {core}
        want = os.SCHED_IDLE if idle else os.SCHED_OTHER
        assert os.sched_getscheduler(child.pid) == want
    finally:
        child.kill()
        child.wait()
