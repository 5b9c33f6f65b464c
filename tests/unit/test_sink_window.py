"""The sinks' bounded window (cosim/sink_window.py, issue #41 item 3): the chain never waits
for a sink inside the window, waits beyond it until the sink reports progress, and ends the
run naming a sink that stops."""

from __future__ import annotations

import threading
import time

import pytest

from cosim import keys
from cosim.auth import RunKey
from cosim.errors import RunError
from cosim.participant import Participant
from cosim.sink_window import MIN_WINDOW, SinkWindow, window_steps
from tests.memory_bus import MemoryBus

KEY = RunKey(b"k" * 32)


def _nodes(stall_s: float = 10.0) -> tuple[Participant, Participant]:
    bus = MemoryBus()
    bus.token(keys.key("r", keys.ORCHESTRATOR, keys.ALIVE))  # the orchestrator is there
    return (Participant(bus, "r", "plant", stall_timeout_s=stall_s, auth=KEY),
            Participant(bus, "r", "recorder", auth=KEY))


def test_the_window_in_steps_is_never_narrower_than_a_records_batch() -> None:
    assert window_steps(0.0, 1e-3) == 0  # unbounded
    assert window_steps(10.0, 5e-4) == 20_000
    assert window_steps(0.001, 1e-3) == MIN_WINDOW


def test_inside_the_window_the_chain_does_not_wait() -> None:
    plant, _ = _nodes()
    w = SinkWindow(plant, ["recorder"], 200)
    t0 = time.monotonic()
    for k in range(200):  # the recorder has said nothing (k = -1): 200 steps may go ahead
        w.hold(k)
    assert w.held_s == 0.0 and time.monotonic() - t0 < 1.0


def test_beyond_the_window_the_chain_waits_for_the_sinks_progress() -> None:
    plant, recorder = _nodes()
    w = SinkWindow(plant, ["recorder"], 200)
    ok = threading.Event()

    def step_500() -> None:
        w.hold(500)
        ok.set()

    th = threading.Thread(target=step_500)
    th.start()
    time.sleep(0.3)
    assert not ok.is_set()  # the recorder is at -1: 501 steps behind step 500
    recorder.ctl("progress", 250, 0.25, rejected=0)
    time.sleep(0.3)
    assert not ok.is_set()  # 250 < 500 - 200
    recorder.ctl("progress", 300, 0.3, rejected=0)
    assert ok.wait(2.0)
    th.join()
    assert w.held_s >= 0.5
    recorder.ctl("done", 1000, 1.0, rejected=0)
    w.hold(10_000)  # a sink that is done is never behind


def test_an_unsigned_progress_does_not_release_the_chain() -> None:
    plant, _ = _nodes(stall_s=0.5)
    w = SinkWindow(plant, ["recorder"], 200)
    bus = plant.bus
    forged = Participant(bus, "r", "recorder")  # no run key
    forged.ctl("progress", 900, 0.9, rejected=0)
    with pytest.raises(RunError, match="sink 'recorder' is 500 steps behind"):
        w.hold(500)


def test_a_sink_that_stops_ends_the_run_naming_it() -> None:
    plant, recorder = _nodes(stall_s=0.4)
    w = SinkWindow(plant, ["recorder", "fatigue"], 200)
    recorder.ctl("progress", 1000, 1.0, rejected=0)
    t0 = time.monotonic()
    with pytest.raises(RunError, match="sink 'fatigue' is 1001 steps behind .* no progress "
                                       "for 0.4 s"):
        w.hold(1001)
    assert 0.35 < time.monotonic() - t0 < 3.0


def test_an_abort_ends_the_wait() -> None:
    plant, _ = _nodes()
    w = SinkWindow(plant, ["recorder"], 200)
    from cosim.wire import encode

    clock = keys.key("r", keys.ORCHESTRATOR, keys.CLOCK)
    threading.Timer(0.2, lambda: plant.bus.put(clock, KEY.signer(clock)(
        encode("abort", -1, 0.0, {"reason": "test"})))).start()
    with pytest.raises(RunError, match="aborted by the orchestrator: test"):
        w.hold(500)


@pytest.mark.integration
def test_a_narrow_window_changes_nothing_in_the_results(tmp_path) -> None:
    """A distributed run whose sinks may lag only MIN_WINDOW steps (the chain waits for the
    recorder's rate-limited progress) completes with the unbounded run's table, byte for
    byte, and says how long the chain waited."""
    import filecmp
    import json

    from tests.conftest import ROOT, suscosim

    out = {}
    for w in ("0", "0.001"):
        res = suscosim("run", str(ROOT / "scenarios" / "ch3_step_quarter_car.toml"), "--out",
                       str(tmp_path / w), "--quiet", "--mode", "distributed", "--set",
                       "run.t_end=0.6", "--set", f"run.sink_window_s={w}", timeout=300)
        assert res.returncode == 0, res.stdout + res.stderr
        out[w] = json.loads((tmp_path / w / "summary.json").read_text())
    assert filecmp.cmp(tmp_path / "0" / "table.csv", tmp_path / "0.001" / "table.csv",
                       shallow=False)
    assert out["0"]["sink_window_held_s"] == 0.0
    assert out["0.001"]["sink_window_held_s"] >= 0.0 and out["0.001"]["rows"] == 601
