"""The sending side of a node (cosim.outbox): one step message a step, messages held for the
next step, and records batches sent after the step they fell due with (issue #28)."""

from __future__ import annotations

from cosim import keys, outbox
from cosim.outbox import RECORD_BATCH, Outbox
from cosim.wire import decode, inner
from tests.memory_bus import MemoryBus

STATE = {"z_b": 0.1, "v_b": 0.0, "z_w": 0.05, "v_w": 0.0}
RESPONSE = {"a_b": 1.0, "a_w": 2.0, "F_t": 3000.0, "F_d": 10.0, "F_s": 2500.0}


def _plant() -> tuple[list[tuple[str, bytes]], Outbox]:
    """The plant's outbox on an in-memory bus, and what it puts (key tail, raw), in order."""
    bus = MemoryBus()
    sent: list[tuple[str, bytes]] = []
    bus.subscribe("suscosim/r/plant/**", lambda key, raw: sent.append((key.rsplit("/", 1)[1],
                                                                        raw)))
    out = Outbox(bus.publisher, "r", "plant")
    for channel in ("state", "response"):
        out.output(channel)
    return sent, out


def _inner(raw: bytes) -> list[tuple[str, int]]:
    return [(channel, decode(one).k) for channel, one in inner(decode(raw))]


def test_held_messages_go_with_the_next_step_oldest_first() -> None:
    sent, out = _plant()
    out.publish("state", 0, 0.0, STATE)
    out.send()
    out.publish("response", 0, 0.0, RESPONSE, hold=True)  # while the plant waits
    out.send()  # the wait's send: nothing of this step yet, so nothing goes
    assert [tail for tail, _ in sent] == ["step"]
    assert _inner(sent[0][1]) == [("state", 0)]
    out.publish("state", 1, 1e-3, STATE)
    out.send()
    assert _inner(sent[1][1]) == [("response", 0), ("state", 1)]
    assert decode(sent[1][1]).k == 1  # the step message's k: its newest message's
    out.publish("response", 1, 1e-3, RESPONSE, hold=True)
    out.publish("response", 2, 2e-3, RESPONSE)  # the last step's: no next step to wait for
    out.flush()  # the end (or a checkpoint): what is held goes too, in order
    steps = [raw for tail, raw in sent if tail == keys.STEP]
    assert _inner(steps[2]) == [("response", 1), ("response", 2)]


def test_a_records_batch_that_falls_due_goes_after_the_step_not_before(monkeypatch) -> None:
    monkeypatch.setattr(outbox, "RECORD_PERIOD_S", 1e9)  # due by count only, here
    sent, out = _plant()
    for k in range(RECORD_BATCH):  # the batch's last message is a state's
        out.publish("state", k, k * 1e-3, STATE)
        if k < RECORD_BATCH - 1:
            out.send()
    assert [tail for tail, _ in sent] == ["step"] * (RECORD_BATCH - 1)  # due, not sent yet
    out.send()
    assert [tail for tail, _ in sent[-2:]] == [keys.STEP, keys.RECORDS]
    records = decode(sent[-1][1])
    assert [decode(raw).k for _, raw in inner(records)] == list(range(RECORD_BATCH))
