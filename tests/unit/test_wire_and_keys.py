import msgpack
import numpy as np
import pytest

from cosim import keys
from cosim.bus import keyexpr_matches
from cosim.errors import ScenarioError, WireError
from cosim.wire import SCHEMA_VERSION, decode, encode


def test_roundtrip_keeps_step_time_and_fields():
    raw = encode("data", 7, 0.007, {"z_w": np.array([0.01]), "F": np.array([1.0, 2.0]), "x": 3})
    msg = decode(raw)
    assert (msg.kind, msg.k, msg.t) == ("data", 7, 0.007)
    assert msg.d == {"z_w": 0.01, "F": [1.0, 2.0], "x": 3}  # length-1 array -> plain number
    assert msg.array("F").tolist() == [1.0, 2.0]


@pytest.mark.parametrize("raw, words", [
    (b"\xc1garbage", "not msgpack"),
    (msgpack.packb([1, 2]), "expected a map"),
    (msgpack.packb({"v": 99, "kind": "data", "k": 0, "t": 0.0, "d": {}}), "version 99"),
    (msgpack.packb({"v": SCHEMA_VERSION, "kind": "nope", "k": 0, "t": 0.0, "d": {}}), "kind"),
    (msgpack.packb({"v": SCHEMA_VERSION, "kind": "data", "k": -5, "t": 0.0, "d": {}}), "k=-5"),
    (msgpack.packb({"v": SCHEMA_VERSION, "kind": "data", "k": 1, "t": "x", "d": {}}), "time"),
    (msgpack.packb({"v": SCHEMA_VERSION, "kind": "data", "k": 1, "t": 0.0, "d": {"F": "a"}}),
     "field 'F'"),
])
def test_decode_rejects_with_a_reason(raw, words):
    with pytest.raises(WireError, match=words):
        decode(raw)


def test_missing_field_is_named():
    with pytest.raises(WireError, match="no field 'F_t'"):
        decode(encode("data", 0, 0.0, {"k_t": 1.0})).array("F_t")


def test_key_scheme_and_names():
    assert keys.key("r1", "plant", "state") == "suscosim/r1/plant/state"
    assert keys.parse_key("suscosim/r1/plant/state") == ("r1", "plant", "state")
    with pytest.raises(ScenarioError, match="run"):
        keys.check_name("run", "a/b")
    with pytest.raises(ScenarioError):
        keys.check_name("run", "**")


def test_keyexpr_matching_of_memory_bus():
    assert keyexpr_matches("suscosim/r1/**", "suscosim/r1/plant/state")
    assert keyexpr_matches("suscosim/r1/*/ctl", "suscosim/r1/plant/ctl")
    assert not keyexpr_matches("suscosim/r1/*/ctl", "suscosim/r2/plant/ctl")
    assert not keyexpr_matches("suscosim/r1/plant/*", "suscosim/r1/plant/state/x")


def test_records_batch_round_trips_the_raw_messages_and_rejects_bad_payloads():
    import msgpack
    import pytest

    from cosim.errors import WireError
    from cosim.wire import decode, encode

    raws = [("state", encode("data", k, 0.001 * k, {"z_b": 0.1 * k})) for k in range(3)]
    msg = decode(encode("records", 2, 0.002, {"records": raws}))
    assert msg.kind == "records" and msg.k == 2
    assert [tuple(r) for r in msg.d["records"]] == raws  # byte for byte, in order
    bad = msgpack.packb({"v": 1, "kind": "records", "k": 0, "t": 0.0,
                         "d": {"records": [["state", "not bytes"]]}}, use_bin_type=True)
    with pytest.raises(WireError, match="records payload"):
        decode(bad)
