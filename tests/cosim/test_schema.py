"""Issue #28 item 1 / #30 item 14: the channel schema declared once, and what is derived from
it: the codec's plausibility checks (compiled), the registry's coupling fields and outputs,
the docs table."""

from __future__ import annotations

import math
from pathlib import Path

import msgpack
import pytest

from cosim import keys, schema
from cosim import node_kinds as nk
from cosim.auth import RunKey
from cosim.errors import RunError, WireError
from cosim.participant import Participant
from cosim.wire import decode, encode, encode_step
from tests.memory_bus import MemoryBus

ROOT = Path(__file__).resolve().parents[2]


def test_the_docs_table_is_the_schemas() -> None:
    text = (ROOT / "docs" / "cosim.md").read_text()
    begin, end = "<!-- schema-table:begin -->\n", "\n<!-- schema-table:end -->"
    assert text[text.index(begin) + len(begin):text.index(end)] == schema.doc_table()


def test_the_registry_takes_outputs_and_coupling_fields_from_the_schema() -> None:
    assert nk.kind("tyre_road").provides == ("F_t", "k_t")
    assert nk.kind("controller").provides == ("F_d", "c_eff")
    assert nk.kind("plant").writes == ("state", "response", "arm", "upper_arm", "arm_FL",
                                       "arm_FR", "arm_RL", "arm_RR", "step", "records")
    assert schema.required("plant", "state") == ("z_b", "v_b", "z_w", "v_w")
    assert schema.columns("tyre_road", "force") == [
        "tyre_road/force/F_t", "tyre_road/force/k_t", "tyre_road/force/z_g",
        "tyre_road/force/Fx", "tyre_road/force/Fy", "tyre_road/force/Mz",
        "tyre_road/force/kappa", "tyre_road/force/alpha"]


@pytest.mark.parametrize("channel, d, t, words", [
    ("plant/state", {"z_b": math.nan}, 0.0, "z_b.*implausible"),
    ("plant/state", {"z_b": 1e308}, 0.0, "z_b.*implausible"),
    ("plant/state", {"z_w": [0.0, math.inf]}, 0.0, "z_w.*implausible"),
    ("plant/state", {"z_b": 0.0}, -1.0, "t >= 0"),
    ("tyre_road/force", {"F_t": -5.0, "k_t": 1.0}, 0.0, "F_t.*negative"),
    ("fatigue/damage", {"max_damage": math.nan}, 0.0, "NaN"),
])
def test_an_implausible_data_message_is_refused_naming_the_field(channel, d, t, words) -> None:
    raw = encode("data", 3, t, d)
    assert decode(raw).d  # as a tap reads it: well formed
    with pytest.raises(WireError, match=words):
        decode(raw, channel)


def test_plausible_messages_and_undeclared_extras_pass() -> None:
    ok = decode(encode("data", 1, 0.001, {"F_d": 10.0, "c_eff": 1500.0,
                                          "F_demand": math.nan}), "controller/force")
    assert ok.d["F_d"] == 10.0 and math.isnan(ok.d["F_demand"])  # an extra: type-checked only
    life = decode(encode("data", 5, 0.005, {"max_damage": 0.0, "life_km": math.inf}),
                  "fatigue/damage")
    assert life.d["life_km"] == math.inf
    assert decode(encode("data", 2, 0.002, {"state": 1}), "controller/force").d["state"] == 1


def test_the_bytes_are_msgpacks() -> None:
    d = {"z_b": 0.1, "n": 3, "l": [1.0, 2.5], "s": "x", "b": b"\x00", "m": {"a": None}}
    assert encode("ready", -1, 0.0, d) == msgpack.packb(
        {"v": 1, "kind": "ready", "k": -1, "t": 0.0, "d": d}, use_bin_type=True)


def test_an_old_or_unknown_version_is_a_clear_error() -> None:
    raw = msgpack.packb({"v": 0, "kind": "data", "k": 0, "t": 0.0, "d": {}})
    with pytest.raises(WireError, match="unknown schema version 0"):
        decode(raw, "plant/state")


def test_a_producer_refuses_to_publish_what_its_consumers_would_reject() -> None:
    bus = MemoryBus()
    part = Participant(bus, "r", "plant", auth=RunKey(b"k" * 32))
    part.output("state")
    part.publish("state", 0, 0.0, {"z_b": 0.0, "v_b": 0.0, "z_w": 0.0, "v_w": 0.0})
    with pytest.raises(RunError, match="cannot publish plant/state step 1: field 'v_w'"):
        part.publish("state", 1, 0.001, {"z_b": 0.0, "v_b": 0.0, "z_w": 0.0, "v_w": math.nan})
    part.close()


def test_a_validly_signed_insider_step_loses_its_implausible_messages() -> None:
    """#30 item 14 with #28 item 2's step messages: validly signed NaN / 1e308 /
    negative-time data from an insider is rejected and counted; the plausible message of the
    same step is taken. (The recorder's side, a records batch: tests/unit/
    test_recorder_stream.py.)"""
    key = RunKey(b"k" * 32)
    bus = MemoryBus()
    bus.token(keys.key("r", keys.ORCHESTRATOR, keys.ALIVE))
    part = Participant(bus, "r", "tyre_road", auth=key)
    state = part.listen("plant", "state", required=("z_b",))
    good = encode("data", 0, 0.0, {"z_b": 0.1})
    inner = [("state", encode("data", 1, 0.001, {"z_b": math.nan})),
             ("state", encode("data", 2, 0.002, {"z_b": 1e308})),
             ("state", encode("data", 3, -0.003, {"z_b": 0.0})), ("state", good)]
    k = keys.key("r", "plant", keys.STEP)
    bus.put(k, key.sign(k, encode_step(3, 0.003, inner)))
    assert part.wait({state: 0})[state].d == {"z_b": 0.1}
    assert part.rejected == 3
    assert sorted(part.inputs[state].box) == [0]
    part.close()
