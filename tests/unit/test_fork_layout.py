"""The table's layout across a fork whose controller starts afresh (nodes/recorder/recording.py)."""

from __future__ import annotations

import math

import pytest

from nodes.recorder.recording import ForkLayouts


def test_held_records_padded_to_the_union_of_both_laws():
    f = ForkLayouts(["controller"], start_k=3)
    assert f.holds("controller", 2) and not f.holds("controller", 3)
    assert not f.holds("plant", 0)
    for k in range(3):
        f.hold("controller/force", k, k * 0.1, {"F_d": float(k), "c_eff": 1500.0, "i": [1, 2]})
    out = f.release("controller/force", {"F_d": 9.0, "c_eff": 2.0, "c": 2500.0})
    assert [k for k, _t, _d in out] == [0, 1, 2]
    assert set(out[0][2]) == {"F_d", "c_eff", "i", "c"} and math.isnan(out[0][2]["c"])
    assert out[1][2]["F_d"] == 1.0 and out[1][2]["i"] == [1, 2]
    later = f.pad("controller/force", {"F_d": 1.0, "c_eff": 2.0, "c": 3.0})
    assert later["i"][0] != later["i"][0] and len(later["i"]) == 2  # NaN of the list's length
    assert f.pad("plant/state", {"z": 1.0}) == {"z": 1.0}
    assert "controller/force" not in f.held


def test_a_field_of_another_shape_is_refused_naming_it():
    f = ForkLayouts(["controller"], start_k=1)
    f.hold("controller/force", 0, 0.0, {"F_d": 1.0, "x": 2.0})
    with pytest.raises(ValueError, match="'x' is a number in the parent and a list of 4"):
        f.release("controller/force", {"F_d": 1.0, "x": [0.0] * 4})
