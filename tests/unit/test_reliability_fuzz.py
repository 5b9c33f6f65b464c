"""Issue #15: bounded fuzzing of everything that takes bytes from the bus. Random frames,
valid messages with one byte flipped, and well-signed messages with random payloads go into
the verifier, a node's inputs and clock, and the orchestrator's clock: the only outcome is
"taken" or "rejected and counted", never another exception. Deterministic (seeded) and
bounded by a number of cases, not by time."""

from __future__ import annotations

import random
import time

import msgpack

from cosim import auth as au
from cosim import keys
from cosim.errors import RunError
from cosim.participant import Participant
from cosim.wire import KINDS, encode, encode_step
from orchestrator.clock import Clock
from tests.memory_bus import MemoryBus

KEY = au.RunKey(au.derive_run_key(b"fuzz" * 8, "r"))
CASES = 3000


def _value(rng: random.Random, depth: int = 0):
    pick = rng.randrange(9 if depth < 2 else 6)
    return [lambda: rng.randint(-2**63, 2**64 - 1), lambda: rng.uniform(-1e300, 1e300),
            lambda: float(rng.choice(["nan", "inf", "-inf"])), lambda: "x" * rng.randrange(5),
            lambda: rng.random() < 0.5, lambda: None, lambda: bytes(rng.randrange(4)),
            lambda: [_value(rng, depth + 1) for _ in range(rng.randrange(4))],
            lambda: {rng.choice(["rejected", "missing", "info", "n_steps", "h", "outputs",
                                 "message", "exit_code", "rows", "files", "F_t", "k_t"]):
                     _value(rng, depth + 1) for _ in range(rng.randrange(4))}][pick]()


def _frames(rng: random.Random, where: str):
    """Random bytes, flipped valid messages, and signed messages with random payloads."""
    for i in range(CASES):
        kind = rng.choice(sorted(KINDS))
        body = msgpack.packb({"v": 1, "kind": kind, "k": rng.randint(-3, 10**6),
                              "t": rng.random(), "d": {"rejected": _value(rng),
                                                       "F_t": _value(rng),
                                                       "k_t": _value(rng),
                                                       "info": _value(rng),
                                                       "missing": _value(rng),
                                                       "n_steps": _value(rng),
                                                       "h": _value(rng)}})
        if i % 3 == 0:
            yield bytes(rng.randrange(256) for _ in range(rng.randrange(40)))
        elif i % 3 == 1:
            raw = bytearray(KEY.sign(where, body))
            raw[rng.randrange(len(raw))] ^= 1 << rng.randrange(8)
            yield bytes(raw)
        else:
            yield KEY.sign(where, body)


def test_a_node_takes_or_rejects_every_frame_on_its_inputs_and_clock() -> None:
    rng = random.Random(15)
    bus = MemoryBus()
    bus.token(keys.key("r", keys.ORCHESTRATOR, keys.ALIVE))
    part = Participant(bus, "r", "plant", auth=KEY)
    part.expect_start = {"n_steps": 10, "h": 0.001, "nodes": ["plant"]}
    tyre = part.listen("tyre_road", "force", required=("F_t", "k_t"))
    step = ("tyre_road", keys.STEP)  # the producer's step message carries its force
    for tag in (step, (keys.ORCHESTRATOR, keys.CLOCK)):
        where = keys.key("r", *tag)
        frames = _frames(rng, where)
        if tag == step:  # and well-signed steps around random inner frames
            frames = (*frames, *(KEY.sign(where, encode_step(0, 0.0, [("force", f)]))
                                 for f in _frames(rng, keys.key("r", "tyre_road", "force"))))
        for raw in frames:
            try:
                part.handle(tag, raw)
            except RunError as exc:  # a signed, well-formed abort is obeyed
                assert "aborted by the orchestrator" in str(exc)
    assert part.rejected > CASES  # every random and flipped frame at least
    assert len(part.inputs[tyre].box) <= 70
    part.close()


def test_the_orchestrator_takes_or_rejects_every_control_frame() -> None:
    rng = random.Random(7)
    scenario = {"run": {"n_steps": 10, "h": 0.001, "start_timeout_s": 5.0,
                        "stall_timeout_s": 5.0}}
    clock = Clock(MemoryBus(), "r", ["plant"], scenario, auth=KEY)
    clock._last_tick = time.monotonic()
    where = keys.key("r", "plant", keys.CTL)
    n = 0
    for raw in _frames(rng, where):
        clock.events.put(("ctl", where, raw))
        n += 1
        if n % 100 == 0:
            try:
                clock._pump(0)
            except RunError as exc:  # a signed, well-formed node error ends the run
                assert "node 'plant'" in str(exc)
                clock = Clock(MemoryBus(), "r", ["plant"], scenario, auth=KEY)
                clock._last_tick = time.monotonic()
    st = clock.status["plant"]
    assert isinstance(st.rejected, int) and isinstance(st.k, int) and st.k <= 10


def test_signed_data_with_every_kind_of_bad_field_is_rejected() -> None:
    bus = MemoryBus()
    part = Participant(bus, "r", "plant", auth=KEY)
    tyre = part.listen("tyre_road", "force", required=("F_t",))
    step = ("tyre_road", keys.STEP)
    where = keys.key("r", *step)
    bad = [{"F_t": "x"}, {"F_t": None}, {"F_t": []}, {"F_t": [1.0, "a"]}, {"k_t": 1.0},
           {"F_t": {"a": 1}}, {"F_t": True}]
    for j, d in enumerate(bad):
        part.handle(step, KEY.sign(where, encode_step(j, 0.0, [
            ("force", encode("data", j, 0.0, d))])))
    assert part.rejected == len(bad) and not part.inputs[tyre].box
    part.close()
