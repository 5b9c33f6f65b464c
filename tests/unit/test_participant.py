"""The lock-step participant on the in-memory bus: step barrier, wake-ups, batches."""

from __future__ import annotations

import threading
import time

import pytest

from cosim import keys
from cosim.auth import RunKey
from cosim.errors import RunError, WireError
from cosim.participant import Participant
from cosim.wire import MAX_MESSAGE_BYTES, decode, encode, encode_step
from tests.memory_bus import MemoryBus


def _pair(stall_s: float = 10.0) -> tuple[MemoryBus, Participant]:
    bus = MemoryBus()
    bus.token(keys.key("r", keys.ORCHESTRATOR, keys.ALIVE))  # the orchestrator is there
    return bus, Participant(bus, "r", "plant", stall_timeout_s=stall_s)


def _put(bus: MemoryBus, node: str, channel: str, raw: bytes) -> None:
    """``raw`` as its producer sends it: a data message in the producer's step message,
    anything else (control, garbage) as it is on the producer's step key."""
    if node == keys.ORCHESTRATOR:
        bus.put(keys.key("r", node, channel), raw)
        return
    try:
        msg = decode(raw)
    except WireError:
        msg = None
    if msg is not None and msg.kind == "data":
        raw = encode_step(msg.k, msg.t, [(channel, raw)])
    bus.put(keys.key("r", node, keys.STEP), raw)


def test_wait_returns_the_step_asked_for_and_drops_older_ones() -> None:
    bus, part = _pair()
    tyre = part.listen("tyre_road", "force", required=("F_t",))
    for k in (0, 1, 2):
        _put(bus, "tyre_road", "force", encode("data", k, k * 1e-3, {"F_t": 10.0 * k}))
    assert part.wait({tyre: 1})[tyre].d["F_t"] == 10.0
    assert sorted(part.inputs[tyre].box) == [1]  # step 0 dropped; step 2 not read yet
    assert part.wait({tyre: 2})[tyre].d["F_t"] == 20.0
    late = threading.Timer(0.1, _put, (bus, "tyre_road", "force",
                                        encode("data", 3, 3e-3, {"F_t": 30.0})))
    late.start()  # arrives while the node is blocked on the input
    assert part.wait({tyre: 3})[tyre].d["F_t"] == 30.0
    part.close()


def test_stall_timeout_wakes_a_blocked_node_and_names_the_silent_input() -> None:
    bus, part = _pair(stall_s=0.3)
    tyre = part.listen("tyre_road", "force")
    damper = part.listen("controller", "force")
    _put(bus, "tyre_road", "force", encode("data", 0, 0.0, {"F_t": 1.0}))
    t0 = time.monotonic()
    with pytest.raises(RunError, match="no input from controller") as err:
        part.wait({tyre: 0, damper: 0})
    assert "tyre_road" not in str(err.value)
    assert 0.3 <= time.monotonic() - t0 < 2.0
    part.close()


def test_abort_reaches_a_node_blocked_on_an_input() -> None:
    bus, part = _pair()
    tyre = part.listen("tyre_road", "force")
    abort = encode("abort", -1, 0.0, {"reason": "node 'controller' is gone"})
    threading.Timer(0.2, _put, (bus, keys.ORCHESTRATOR, keys.CLOCK, abort)).start()
    t0 = time.monotonic()
    with pytest.raises(RunError, match="aborted.*controller"):
        part.wait({tyre: 0})
    assert time.monotonic() - t0 < 2.0  # not the 10 s stall timeout
    part.close()


def test_empty_and_malformed_messages_on_an_input_are_rejected_not_fatal() -> None:
    bus, part = _pair()
    tyre = part.listen("tyre_road", "force", required=("F_t",))
    for raw in (b"", b"\xc1", encode("data", 0, 0.0, {"k_t": 1.0})):
        _put(bus, "tyre_road", "force", raw)
    _put(bus, "tyre_road", "force", encode("data", 0, 0.0, {"F_t": 5.0}))
    assert part.wait({tyre: 0})[tyre].d["F_t"] == 5.0
    assert part.rejected == 3
    part.close()


def test_records_batches_stay_under_the_message_limit() -> None:
    bus, part = _pair()
    part.output("arm")
    batches: list[bytes] = []
    bus.subscribe(keys.key("r", "plant", keys.RECORDS), lambda _k, raw: batches.append(raw))
    fields = {f"f{i}": [0.1 * i] * 200 for i in range(10)}  # ~18 kB a message
    for k in range(5):
        part.publish("arm", k, k * 1e-3, fields)
    part.flush_records()
    sizes = [len(b) for b in batches]
    assert len(batches) >= 2 and max(sizes) <= MAX_MESSAGE_BYTES, sizes
    got = [decode(raw).k for b in batches for _, raw in decode(b).d["records"]]
    assert got == list(range(5))
    with pytest.raises(RunError, match="plant/arm.*bytes"):
        part.publish("arm", 5, 5e-3, {"x": [1.0] * 10_000})
    part.close()


def test_finish_keeps_draining_inputs_until_the_orchestrator_closes_the_run() -> None:
    bus, part = _pair()
    tyre = part.listen("tyre_road", "force")
    for k in range(5):  # a producer still publishing after this node's last step
        _put(bus, "tyre_road", "force", encode("data", k, k * 1e-3, {"F_t": 1.0}))
    done = encode("done", 4, 4e-3, {})
    threading.Timer(0.3, _put, (bus, keys.ORCHESTRATOR, keys.CLOCK, done)).start()
    t0 = time.monotonic()
    part.finish(4, 4e-3)
    assert time.monotonic() - t0 < 5.0  # left on the orchestrator's "done", not the linger
    assert part.feeds[tyre].try_recv() is None  # nothing left to fill the FIFO
    part.close()


def test_a_spinning_node_still_gets_its_input_and_still_sees_a_stall() -> None:
    bus, part = _pair(stall_s=0.5)
    part.spin_s = 0.2  # polls 200 ms before blocking
    tyre = part.listen("tyre_road", "force")
    threading.Timer(0.05, _put, (bus, "tyre_road", "force",
                                 encode("data", 0, 0.0, {"F_t": 7.0}))).start()
    assert part.wait({tyre: 0})[tyre].d["F_t"] == 7.0  # arrives while polling
    threading.Timer(0.3, _put, (bus, "tyre_road", "force",
                                encode("data", 1, 1e-3, {"F_t": 8.0}))).start()
    assert part.wait({tyre: 1})[tyre].d["F_t"] == 8.0  # arrives after the poll: blocked
    with pytest.raises(RunError, match="no input from tyre_road"):
        part.wait({tyre: 2})
    part.close()


def test_a_producer_sends_one_signed_message_a_step_that_feeds_each_input() -> None:
    """#28 item 2: the plant's state of step k and its response of step k - 1 go out as ONE
    message on plant/step (signed once); a consumer listening to both channels files each
    from it, and a hello on the step proves both inputs live."""
    key = RunKey(b"k" * 32)
    bus = MemoryBus()
    bus.token(keys.key("r", keys.ORCHESTRATOR, keys.ALIVE))
    plant = Participant(bus, "r", "plant", auth=key)
    ctrl = Participant(bus, "r", "controller", auth=key)
    state = ctrl.listen("plant", "state", required=("z_b",))
    resp = ctrl.listen("plant", "response")
    sent: list[tuple[str, bytes]] = []
    bus.subscribe("suscosim/r/plant/**", lambda k, raw: sent.append((k, raw)))
    for channel in ("state", "response"):
        plant.output(channel)
    plant.publish_hello()
    ctrl._drain_feeds()
    assert ctrl.inputs[state].heard and ctrl.inputs[resp].heard
    sent.clear()
    plant.publish("state", 1, 1e-3, {"z_b": 0.5})
    plant.publish("response", 0, 0.0, {"a_b": 2.0})
    assert not sent  # nothing goes out before the step is sent
    plant.send()
    assert [k for k, _ in sent] == ["suscosim/r/plant/step"]
    assert key.verify(sent[0][0], sent[0][1])  # signed once, for the step's key
    got = ctrl.wait({state: 1, resp: 0})
    assert got[state].d == {"z_b": 0.5} and got[resp].d == {"a_b": 2.0}
    plant.flush_records()
    (batch,) = [decode(raw) for k, raw in sent if k.endswith("/records")]
    assert [c for c, _ in batch.d["records"]] == ["state", "response"]  # the journal's, as before
    for p in (plant, ctrl):
        p.close()
