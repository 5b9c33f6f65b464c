"""Ride metrics of the lower arm's point accelerations (Table 5.4) and of the full vehicle's
pitch and roll accelerations (Tables 5.7-5.10), on sines of known amplitude."""

from __future__ import annotations

import numpy as np
import pytest

from nodes.recorder.ride_metrics import ARM_ACCEL_FIELDS, metric_values, ride_summary

FS = 500.0
T = np.arange(0.0, 20.0, 1.0 / FS)


def _table(**cols):
    return {"t": T, **{f"plant/response/{k}": v for k, v in cols.items()}}


def test_arm_point_rms_is_the_band_rms_of_each_field():
    cols = {name: (i + 1) * 0.1 * np.sin(2 * np.pi * 3.0 * T)
            for i, name in enumerate(ARM_ACCEL_FIELDS)}
    m = metric_values(_table(**cols))
    for i, name in enumerate(ARM_ACCEL_FIELDS):
        value, unit, _ = m[f"{name}_rms"]
        assert unit == "m/s2"
        assert value == pytest.approx((i + 1) * 0.1 / np.sqrt(2), rel=5e-3)


def test_pitch_and_roll_rms_in_both_bands():
    # 5 Hz pitch in both bands; an 18 Hz roll tone is in 0-20 Hz but not in 0-16 Hz
    pitch = 0.4 * np.sin(2 * np.pi * 5.0 * T)
    roll = 0.3 * np.sin(2 * np.pi * 18.0 * T)
    m = metric_values(_table(alpha_pitch=pitch, alpha_roll=roll))
    assert m["alpha_pitch_rms"][1] == "rad/s2"
    assert m["alpha_pitch_rms"][0] == pytest.approx(0.4 / np.sqrt(2), rel=5e-3)
    assert m["alpha_pitch_rms_0_16"][0] == pytest.approx(0.4 / np.sqrt(2), rel=5e-3)
    assert m["alpha_roll_rms"][0] == pytest.approx(0.3 / np.sqrt(2), rel=5e-3)
    # only the rectangular window's leakage below 16 Hz (about 4 %)
    assert m["alpha_roll_rms_0_16"][0] < 0.1 * m["alpha_roll_rms"][0]


def test_pitch_change_against_the_baseline():
    base = _table(alpha_pitch=0.4 * np.sin(2 * np.pi * 2.0 * T))
    half = _table(alpha_pitch=0.2 * np.sin(2 * np.pi * 2.0 * T))
    s = ride_summary({"passive": base, "law": half})
    assert s["units"]["alpha_pitch_rms"] == "rad/s2"
    assert s["runs"][1]["change_pct"]["alpha_pitch_rms"] == pytest.approx(50.0, abs=0.5)


def test_tables_without_the_fields_have_no_such_metrics():
    m = metric_values(_table(a_b=np.sin(2 * np.pi * T)))
    assert not any(k.startswith(("a_arm", "alpha")) for k in m)
