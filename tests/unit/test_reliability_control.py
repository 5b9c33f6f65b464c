"""Issue #15 items 4, 6 and 7: control messages checked field by field and for plausibility
by the clock; bounded mailboxes; ragged ``records`` batches rejected by the recorder."""

from __future__ import annotations

import queue
import threading
import time
from pathlib import Path

import pytest

from cosim import auth as au
from cosim import keys
from cosim.errors import InputLate
from cosim.journal import read_journal
from cosim.participant import MAILBOX_MAX, MAILBOX_WINDOW, Participant
from cosim.table_writer import journal_table
from cosim.wire import encode, encode_step
from orchestrator.clock import Clock
from tests.memory_bus import MemoryBus

KEY = au.derive_run_key(b"k" * 32, "r")
N = 10


def _clock(auth: au.RunKey | None = None) -> Clock:
    scenario = {"run": {"n_steps": N, "h": 0.001, "start_timeout_s": 5.0,
                        "stall_timeout_s": 5.0}}
    clock = Clock(MemoryBus(), "r", ["plant", "recorder"], scenario, auth=auth)
    clock._last_tick = time.monotonic()
    return clock


def _feed(clock: Clock, node: str, raw: bytes) -> None:
    clock.events.put(("ctl", keys.key("r", node, keys.CTL), raw))
    clock._pump(0.01)


@pytest.mark.parametrize("kind,k,d", [
    ("progress", 3, {"rejected": "lots"}),   # #15 item 7: ValueError in the orchestrator
    ("progress", 3, {"rejected": -1}),
    ("waiting", -1, {"missing": 5}),         # #15 item 7: TypeError in the orchestrator
    ("waiting", -1, {"missing": ["a", 3]}),
    ("ready", -1, {"info": [1, 2]}),
    ("ready", -1, {"info": {"outputs": "state"}}),
    ("error", -1, {"message": "x", "exit_code": "2"}),
    ("error", -1, {"message": 7}),
    ("done", N, {"rows": "many"}),
    ("done", N, {"files": {"csv": 3}}),
    ("done", N, {"torn": "no"}),
    ("done", 5, {"rejected": 0}),            # implausible: done before the last step
    ("progress", N + 1, {"rejected": 0}),   # implausible: beyond the last step
    ("start", -1, {}),                       # not a node's kind
])
def test_malformed_or_implausible_control_messages_are_rejected_not_fatal(kind, k, d) -> None:
    clock = _clock()
    _feed(clock, "plant", encode(kind, k, 0.0, d))
    st = clock.status["plant"]
    assert clock.rejected == 1
    assert not st.ready and not st.done and st.k == -1 and st.rejected == 0
    _feed(clock, "plant", encode("progress", 4, 0.004, {"rejected": 2}))  # a good one still counts
    assert st.k == 4 and st.rejected == 2 and clock.rejected == 1


def test_the_clock_takes_only_control_messages_signed_with_the_run_key() -> None:
    """#15 item 4: ``done`` on the nodes' ctl keys gave a fabricated summary and no table."""
    clock = _clock(au.RunKey(KEY))
    done = encode("done", N, N * 1e-3, {"rejected": 0, "rows": 99999})
    _feed(clock, "recorder", done)  # unsigned
    _feed(clock, "recorder", au.RunKey(au.derive_run_key(b"k" * 32, "r2")).sign(
        keys.key("r", "recorder", keys.CTL), done))  # another run's key
    _feed(clock, "recorder", au.RunKey(KEY).sign(keys.key("r", "plant", keys.CTL), done))
    assert clock.rejected == 3 and not clock.status["recorder"].done
    _feed(clock, "recorder", au.RunKey(KEY).sign(keys.key("r", "recorder", keys.CTL), done))
    assert clock.status["recorder"].done and clock.status["recorder"].result["rows"] == 99999


def test_a_node_that_gives_up_on_a_silent_producer_gets_the_producer_blamed() -> None:
    """#30 item 15: a node's stall timeout and the clock's are the same, so which notices a
    paused producer first is a race (CI: "node 'controller': no input from plant"); the
    error names the producer either way, and the node that noticed as waiting for it."""
    clock = _clock()
    _feed(clock, "plant", encode("progress", 3, 0.003, {"rejected": 0}))
    msg = "recorder: no input from plant for 5.0 s (step 4)"
    with pytest.raises(Exception) as err:
        _feed(clock, "recorder", encode("error", -1, 0.0, {"message": msg, "exit_code": 1,
                                                           "late": ["plant"]}))
    text = str(err.value)
    assert text.startswith("node 'plant' made no progress for 5.0 s (stalled at step 3 of 10)")
    assert "waiting for it: recorder (" + msg + ")" in text
    clock = _clock()  # without 'late' the node that failed is the one named
    with pytest.raises(Exception) as err:
        _feed(clock, "recorder", encode("error", -1, 0.0, {"message": "disk full"}))
    assert str(err.value) == "node 'recorder': disk full"
    clock = _clock()
    _feed(clock, "recorder", encode("error", -1, 0.0, {"message": "x", "late": "plant"}))
    assert clock.rejected == 1  # a malformed 'late' is rejected, not believed


def test_a_late_input_names_its_producer_in_the_error() -> None:
    bus = MemoryBus()
    part = Participant(bus, "r", "recorder")
    part.stall_timeout_s = 0.2
    tag = part.listen("plant", "state")
    try:
        with pytest.raises(InputLate) as err:
            part.wait({tag: 0})
    finally:  # else its watchdog thread lived to the interpreter's exit (named by CI)
        part.close()
    assert err.value.late == ["plant"] and "no input from plant" in str(err.value)


def test_far_ahead_steps_are_rejected_and_the_mailbox_stays_bounded() -> None:
    """#15 item 6: distinct far-ahead step indices made every wait() scan them all (the run
    never finished and no stall was seen). Now a window of steps; beyond it, rejected."""
    bus = MemoryBus()
    bus.token(keys.key("r", keys.ORCHESTRATOR, keys.ALIVE))
    part = Participant(bus, "r", "plant")
    tyre = part.listen("tyre_road", "force", required=("F_t",))
    step = keys.key("r", "tyre_road", keys.STEP)

    def put(k: int, t: float, F_t: float) -> None:  # as the producer sends it: in its step
        bus.put(step, encode_step(k, t, [("force", encode("data", k, t, {"F_t": F_t}))]))

    flood = 20000
    for j in range(flood):
        put(1000 + j, 1.0, 1e6)
    for k in range(3):
        put(k, k * 1e-3, float(k))
        assert part.wait({tyre: k})[tyre].d["F_t"] == float(k)
        assert len(part.inputs[tyre].box) <= MAILBOX_WINDOW + 2
    assert part.rejected == flood
    put(1, 1e-3, 5.0)  # behind the step waited for
    put(2 + MAILBOX_WINDOW + 1, 1.0, 5.0)
    put(2 + MAILBOX_WINDOW, 1.0, 5.0)  # the window's edge
    part._drain_feeds()
    assert part.rejected == flood + 2 and 2 + MAILBOX_WINDOW in part.inputs[tyre].box
    part.close()


def test_an_input_that_is_not_stepped_holds_a_bounded_number_of_messages() -> None:
    bus = MemoryBus()
    part = Participant(bus, "r", "fatigue")
    loads = part.listen("recorder", "loads", required=("k0", "t"), stepped=False)
    for j in range(MAILBOX_MAX + 50):
        part.handle(loads, encode("data", j, 0.0, {"k0": j, "t": [0.0]}))
    assert len(part.inputs[loads].box) == MAILBOX_MAX and part.rejected == 50
    part.close()


def test_a_ragged_records_batch_is_rejected_and_the_journal_stays_exportable(
        tmp_path: Path) -> None:
    """#15 item 7: a ``records`` batch with ragged lists crashed the recorder and made a
    complete journal unexportable. The recorder runs for real here, on the in-memory bus."""
    from nodes.recorder import node as recorder

    bus = MemoryBus()
    bus.token(keys.key("r", keys.ORCHESTRATOR, keys.ALIVE))
    n = 3
    scenario = {"run": {"dir": str(tmp_path), "nodes": ["plant", "recorder"], "h": 1e-3,
                        "start_timeout_s": 10.0, "stall_timeout_s": 10.0, "n_steps": n}}
    part = Participant(bus, "r", "recorder")
    errors: queue.SimpleQueue = queue.SimpleQueue()

    def body() -> None:
        try:
            recorder.run(part, scenario)
        except Exception as exc:  # noqa: BLE001 - asserted below
            errors.put(exc)

    ctl: list[str] = []
    bus.subscribe(keys.key("r", "recorder", keys.CTL),
                  lambda _k, raw: ctl.append(__import__("cosim.wire").wire.decode(raw).kind))
    th = threading.Thread(target=body, daemon=True)
    th.start()
    records = keys.key("r", "plant", keys.RECORDS)
    clock = keys.key("r", keys.ORCHESTRATOR, keys.CLOCK)
    deadline = time.monotonic() + 10
    while "ready" not in ctl and time.monotonic() < deadline:
        bus.put(records, encode("hello", -1, 0.0, {}))  # as a producer does, until ready
        time.sleep(0.02)
    bus.put(clock, encode("start", -1, 0.0, {"n_steps": n, "h": 1e-3,
                                             "info": {"plant": {"outputs": ["state"]},
                                                      "recorder": {}}}))

    def rec(k: int, z: object) -> list:
        return ["state", encode("data", k, k * 1e-3, {"z_b": z, "v_b": 0.0})]

    bus.put(records, encode("records", 1, 1e-3, {"records": [rec(0, 0.0), rec(1, 0.1)]}))
    ragged = [rec(2, [1.0, 2.0]), rec(3, [1.0, 2.0, 3.0]), ["bad/name", b"x"]]
    bus.put(records, encode("records", 3, 3e-3, {"records": ragged}))
    bus.put(records, encode("records", 3, 3e-3, {"records": [rec(2, 0.2), rec(3, 0.3)]}))
    while "done" not in ctl and time.monotonic() < deadline and th.is_alive():
        time.sleep(0.02)
    bus.put(clock, encode("done", n, n * 1e-3, {}))
    th.join(timeout=10)
    assert errors.empty(), errors.get()
    assert "done" in ctl and part.rejected == 3
    table, bad = journal_table(read_journal(tmp_path / "journal.msgpack").records)
    assert bad == 0 and list(table["plant/state/z_b"]) == [0.0, 0.1, 0.2, 0.3]
    assert (tmp_path / "table.csv").exists()
    part.close()
