"""The listener base (cosim/listener.py) of the recorder and the fatigue node: the start
handshake, and every bad message rejected and counted through the participant's public
API, on the in-memory bus with the run's key."""

from __future__ import annotations

import time

import pytest

from cosim import auth as au
from cosim import keys
from cosim.errors import RunError
from cosim.listener import Listener
from cosim.participant import Participant
from cosim.wire import decode, encode
from tests.memory_bus import MemoryBus

KEY = au.RunKey(au.derive_run_key(b"s" * 32, "r"))
LOADS = keys.key("r", "recorder", "loads")
CLOCK = keys.key("r", keys.ORCHESTRATOR, keys.CLOCK)


def _setup(timeout_s: float = 10.0):
    bus = MemoryBus()
    bus.token(keys.key("r", keys.ORCHESTRATOR, keys.ALIVE))
    part = Participant(bus, "r", "fatigue", auth=KEY)
    part.expect_start = {"n_steps": 5, "h": 0.001}
    ctl: list = []
    bus.subscribe(keys.key("r", "fatigue", keys.CTL),
                  lambda _k, raw: ctl.append(decode(KEY.verify(keys.key("r", "fatigue",
                                                                        keys.CTL), raw))))
    lst = Listener(part, timeout_s, info={"what": "test"})
    lst.feed("recorder", "loads", required=("k0", "t"))
    return bus, part, lst, ctl


def _poll_all(lst: Listener, n: int = 20) -> list:
    return [got for _ in range(n) if (got := lst.poll(timeout=0.01)) is not None]


def _start(n_steps: int) -> bytes:
    return KEY.sign(CLOCK, encode("start", -1, 0.0, {"n_steps": n_steps, "h": 0.001,
                                                     "info": {}}))


def test_ready_once_every_feed_is_heard_then_a_plausible_start() -> None:
    bus, part, lst, ctl = _setup()
    _poll_all(lst, 3)
    assert lst.missing() == ["recorder/loads"] and not any(m.kind == "ready" for m in ctl)
    bus.put(LOADS, KEY.sign(LOADS, encode("hello", -1, 0.0, {})))
    deadline = time.monotonic() + 5.0
    while not any(m.kind == "ready" for m in ctl) and time.monotonic() < deadline:
        lst.poll(timeout=0.01)  # every hello period: hello, and ready once all are heard
    ready = [m for m in ctl if m.kind == "ready"]
    assert ready and ready[-1].d["info"] == {"outputs": [], "what": "test"}
    bus.put(CLOCK, _start(99))  # not this scenario's start: rejected, not acted on
    _poll_all(lst, 3)
    assert lst.start is None and part.rejected == 1
    bus.put(CLOCK, _start(5))
    _poll_all(lst, 3)
    assert lst.start is not None and lst.start["n_steps"] == 5
    part.close()


def test_bad_messages_on_a_feed_are_rejected_and_counted() -> None:
    bus, part, lst, _ = _setup()
    good = encode("data", 3, 0.003, {"k0": 0, "t": [0.0]})
    bus.put(LOADS, good)  # unsigned
    bus.put(LOADS, au.RunKey(au.derive_run_key(b"x" * 32, "r")).sign(LOADS, good))  # a stranger
    bus.put(LOADS, KEY.sign(LOADS, encode("records", 3, 0.0, {"records": []})))  # wrong kind
    bus.put(LOADS, KEY.sign(LOADS, encode("data", 3, 0.0, {"t": [0.0]})))  # no k0
    bus.put(LOADS, KEY.sign(LOADS, good))
    got = _poll_all(lst)
    assert part.rejected == 4
    assert [(g.node, g.channel, g.msg.k) for g in got] == [("recorder", "loads", 3)]
    assert lst.heard == {("recorder", "loads")}
    part.close()


def test_an_abort_and_a_missed_start_end_the_node_naming_why() -> None:
    bus, part, lst, _ = _setup()
    bus.put(CLOCK, KEY.sign(CLOCK, encode("abort", -1, 0.0, {"reason": "plant died"})))
    with pytest.raises(RunError, match="plant died"):
        _poll_all(lst)
    part.close()
    _, part, lst, _ = _setup(timeout_s=0.2)
    time.sleep(0.25)
    with pytest.raises(RunError, match="not started within 0 s; never heard recorder/loads"):
        lst.poll(timeout=0.01)
    part.close()
