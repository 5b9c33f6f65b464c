"""Issue #15 item 4: the messages of a run are signed with the run's key; a node takes only
what verifies, a ``start`` must match its scenario, a rogue scenario reply is not run, and a
reader without the key (a tap) still decodes every message."""

from __future__ import annotations

import os
import queue
import threading

import msgpack
import pytest

from cosim import auth as au
from cosim import keys
from cosim.errors import RunError
from cosim.participant import Participant
from cosim.wire import decode, encode, encode_step
from tests.memory_bus import MemoryBus

KEY = au.derive_run_key(b"s" * 32, "r")
OTHER = au.derive_run_key(b"s" * 32, "r2")  # same secret, another run: another key


def _node(auth: au.RunKey | None = None) -> tuple[MemoryBus, Participant]:
    bus = MemoryBus()
    bus.token(keys.key("r", keys.ORCHESTRATOR, keys.ALIVE))
    return bus, Participant(bus, "r", "plant", auth=auth or au.RunKey(KEY))


def _signed(key: bytes, node: str, channel: str, body: bytes) -> bytes:
    return au.RunKey(key).sign(keys.key("r", node, channel), body)


def test_signature_binds_the_run_and_the_channel_and_taps_decode_without_the_key() -> None:
    k = au.RunKey(KEY)
    body = encode("data", 3, 3e-3, {"F_t": 1.0})
    raw = k.sign("suscosim/r/tyre_road/force", body)
    assert k.verify("suscosim/r/tyre_road/force", raw) == raw  # taken as it came
    for where, key in (("suscosim/r/controller/force", KEY),  # replayed on another channel
                       ("suscosim/r/tyre_road/force", OTHER)):  # another run's key
        with pytest.raises(au.AuthError, match="bad signature"):
            au.RunKey(key).verify(where, raw)
    with pytest.raises(au.AuthError, match="unsigned"):
        k.verify("suscosim/r/tyre_road/force", body)
    flipped = bytearray(raw)
    flipped[5] ^= 1
    with pytest.raises(au.AuthError):
        k.verify("suscosim/r/tyre_road/force", bytes(flipped))
    assert decode(raw) == decode(body)  # a tap, without the key
    plain = msgpack.unpackb(raw)  # a plain msgpack reader: one more field, "s"
    assert plain.pop("s") == raw[-16:] and plain == msgpack.unpackb(body)
    with pytest.raises(ValueError):
        k.sign("suscosim/r/tyre_road/force", raw)  # a signed message is not signed again


def test_unsigned_and_badly_signed_inputs_are_rejected_and_counted() -> None:
    bus, part = _node()
    tyre = part.listen("tyre_road", "force", required=("F_t",))
    step = keys.key("r", "tyre_road", keys.STEP)

    def force(F_t: float) -> bytes:
        return encode_step(0, 0.0, [("force", encode("data", 0, 0.0, {"F_t": F_t}))])

    bus.put(step, force(666.0))
    bus.put(step, _signed(OTHER, "tyre_road", keys.STEP, force(667.0)))
    bus.put(step, _signed(KEY, "tyre_road", "force", force(668.0)))  # signed for another key
    bus.put(step, _signed(KEY, "tyre_road", keys.STEP, force(1.0)))
    assert part.wait({tyre: 0})[tyre].d["F_t"] == 1.0
    assert part.rejected == 3
    part.close()


def test_published_messages_are_signed_for_their_key() -> None:
    bus, part = _node()
    got: list[tuple[str, bytes]] = []
    bus.subscribe("suscosim/r/**", lambda k, raw: got.append((k, raw)))
    part.output("state")
    part.publish("state", 0, 0.0, {"z_b": 0.0})
    part.ctl("progress", 0, 0.0, rejected=0)
    part.flush_records()
    assert {k for k, _ in got} == {"suscosim/r/plant/step", "suscosim/r/plant/ctl",
                                   "suscosim/r/plant/records"}  # state: in the step
    for k, raw in got:
        au.RunKey(KEY).verify(k, raw)  # raises if not signed for that key
    part.close()


def _handshake(part: Participant, out: queue.SimpleQueue) -> None:
    try:
        out.put(part.handshake(timeout_s=10.0))
    except Exception as exc:  # noqa: BLE001 - the test asserts on it
        out.put(exc)


def test_a_forged_or_implausible_start_is_not_acted_on() -> None:
    """#15 item 4: one ``start`` with ``n_steps: 5`` made a run end "ok" with 493 of 12001
    rows. Unsigned, signed with another key, or not matching the scenario: rejected."""
    bus, part = _node()
    part.expect_start = {"n_steps": 100, "h": 0.001, "nodes": ["plant", "recorder"]}
    info = {"plant": {}, "recorder": {}}
    clock = keys.key("r", keys.ORCHESTRATOR, keys.CLOCK)
    out: queue.SimpleQueue = queue.SimpleQueue()
    th = threading.Thread(target=_handshake, args=(part, out), daemon=True)
    th.start()
    forged = [
        encode("start", -1, 0.0, {"n_steps": 5, "h": 0.001, "info": info}),  # unsigned
        _signed(OTHER, keys.ORCHESTRATOR, keys.CLOCK,
                encode("start", -1, 0.0, {"n_steps": 5, "h": 0.001, "info": info})),
        _signed(KEY, keys.ORCHESTRATOR, keys.CLOCK,  # signed, but not this scenario's
                encode("start", -1, 0.0, {"n_steps": 5, "h": 0.001, "info": info})),
        _signed(KEY, keys.ORCHESTRATOR, keys.CLOCK,
                encode("start", -1, 0.0, {"n_steps": 100, "h": 0.002, "info": info})),
        _signed(KEY, keys.ORCHESTRATOR, keys.CLOCK,  # a node's facts missing
                encode("start", -1, 0.0, {"n_steps": 100, "h": 0.001, "info": {"plant": {}}})),
        _signed(KEY, keys.ORCHESTRATOR, keys.CLOCK,  # malformed
                encode("start", -1, 0.0, {"n_steps": "100", "h": 0.001, "info": info})),
        encode("abort", -1, 0.0, {"reason": "forged"}),  # an outside abort, unsigned
    ]
    for raw in forged:
        bus.put(clock, raw)
    bus.put(clock, _signed(KEY, keys.ORCHESTRATOR, keys.CLOCK,
                           encode("start", -1, 0.0, {"n_steps": 100, "h": 0.001, "info": info})))
    th.join(timeout=10)
    start = out.get(timeout=1)
    assert not isinstance(start, Exception), start
    assert start["n_steps"] == 100
    assert part.rejected == len(forged)
    part.close()


def test_a_signed_abort_still_ends_the_node() -> None:
    bus, part = _node()
    tyre = part.listen("tyre_road", "force")
    bus.put(keys.key("r", keys.ORCHESTRATOR, keys.CLOCK),
            _signed(KEY, keys.ORCHESTRATOR, keys.CLOCK, encode("abort", -1, 0.0,
                                                               {"reason": "real"})))
    with pytest.raises(RunError, match="aborted by the orchestrator: real"):
        part.wait({tyre: 0})
    part.close()


class _TwoQueryables(MemoryBus):
    """A bus on which a rogue queryable answers the scenario query before the real one."""

    def __init__(self, replies: list[bytes]) -> None:
        super().__init__()
        self.replies = replies

    def query_all(self, key: str, timeout: float = 1.0) -> list[bytes]:
        return list(self.replies)


def test_a_rogue_scenario_queryable_is_not_run() -> None:
    """#15 item 4: a rogue scenario queryable on a router: nodes ran it and wrote where it
    said. Only the reply signed with the run's key is taken."""
    key = keys.key("r", keys.ORCHESTRATOR, keys.SCENARIO)
    nonce = au.new_nonce()
    real = au.RunKey(KEY).sign(key, encode("start", -1, 0.0, {"run": {"dir": "/ok"},
                                                             "session": nonce.hex()}))
    rogue = encode("start", -1, 0.0, {"run": {"dir": "/tmp/evil"}, "session": nonce.hex()})
    rogue_other = au.RunKey(OTHER).sign(key, rogue)
    no_nonce = au.RunKey(KEY).sign(key, encode("start", -1, 0.0, {"run": {"dir": "/old"}}))
    bus = _TwoQueryables([rogue, rogue_other, no_nonce, real])
    part = Participant(bus, "r", "plant", auth=au.RunKey(KEY))
    assert part.fetch_scenario(timeout_s=5) == {"run": {"dir": "/ok"}}
    assert part.rejected == 3
    assert part.auth is not None and part.auth.nonce == nonce  # bound to the run instance
    bus.replies = [rogue]
    with pytest.raises(RunError, match="no orchestrator answered"):
        part.fetch_scenario(timeout_s=0.5)
    part.close()


def test_the_run_key_comes_from_the_environment_or_a_private_key_file(tmp_path) -> None:
    assert au.run_key_from_env("r", {au.ENV_RUN_KEY: KEY.hex()}) == KEY
    secret = au.new_secret()
    path = au.write_secret_file(tmp_path / "run.key", secret)
    assert path.stat().st_mode & 0o777 == 0o600
    assert au.run_key_from_env("r", {au.ENV_KEY_FILE: str(path)}) == \
        au.derive_run_key(secret, "r")
    assert au.run_key_from_env("r", {au.ENV_KEY: "a shared secret, long enough"}) == \
        au.derive_run_key(b"a shared secret, long enough", "r")
    os.chmod(path, 0o644)
    with pytest.raises(au.NoKeyError, match="chmod 600") as err:
        au.run_key_from_env("r", {au.ENV_KEY_FILE: str(path)})
    assert err.value.exit_code == 2
    with pytest.raises(au.NoKeyError, match="--key-file"):
        au.run_key_from_env("r", {})


def test_a_node_without_a_key_exits_2_without_a_word_on_the_bus(monkeypatch) -> None:
    from orchestrator.node_main import run_node

    for name in (au.ENV_RUN_KEY, au.ENV_KEY_FILE, au.ENV_KEY):
        monkeypatch.delenv(name, raising=False)
    bus = MemoryBus()
    said: list[str] = []
    bus.subscribe("suscosim/**", lambda k, raw: said.append(k))
    assert run_node(bus, "r", "plant") == 2
    assert said == []


def test_a_message_of_another_instance_of_the_run_does_not_verify() -> None:
    """#30 item 11: the same key and run id, another nonce: bad signature."""
    key = keys.key("r", "plant", keys.CTL)
    body = encode("done", 5, 0.005, {"rejected": 0})
    one, two = au.RunKey(KEY, au.new_nonce()), au.RunKey(KEY, au.new_nonce())
    assert one.verify(key, one.sign(key, body))
    for other in (two, au.RunKey(KEY)):
        with pytest.raises(au.AuthError, match="bad signature"):
            other.verify(key, one.sign(key, body))
    with pytest.raises(au.AuthError, match="bad signature"):
        one.verify(key, au.RunKey(KEY).sign(key, body))
    with pytest.raises(ValueError, match="nonce"):
        au.RunKey(KEY, b"short")
