"""The adaptive step's numerics (cosim/step_size.py, cosim/table_batches.resampled, the
residual of a non-uniform table): each against a hand calculation or the fixed-step code."""

from __future__ import annotations

import numpy as np
import pytest

from cosim.coupling_stream import ResidualStream
from cosim.step_size import AdaptiveStep, step_residual
from cosim.table_batches import resampled, uniform_grid_size

CTRL = AdaptiveStep(1e-4, 4e-3, 1e-3)


def test_error_is_one_at_the_tolerance():
    assert CTRL.error(dE=1e-3 * 2.0, carried=2.0) == pytest.approx(1.0 / (1 + 1e-6 / 2e-3))
    assert CTRL.error(0.0, 5.0) == 0.0


def test_pi_controller_grows_shrinks_and_clamps():
    h = 1e-3
    # eps = 1 and no history: the safety factor alone
    assert CTRL.next(h, 1.0, None) == pytest.approx(0.9 * h)
    # a large error: cut by the largest allowed change, a tiny one: grown by it
    assert CTRL.next(h, 1e6, None) == pytest.approx(0.5 * h)
    assert CTRL.next(h, 1e-6, None) == pytest.approx(1.5 * h)
    # eps = 0.5, previous 1: 0.9 * 0.5^-(0.4) * 1^0.1
    assert CTRL.next(h, 0.5, 1.0) == pytest.approx(h * 0.9 * 0.5 ** -0.4)
    # the proportional part: a falling error grows the step more than a steady one
    assert CTRL.next(h, 0.5, 2.0) > CTRL.next(h, 0.5, 0.5)
    assert CTRL.next(3.9e-3, 1e-9, None) == 4e-3 and CTRL.next(1.1e-4, 1e9, None) == 1e-4
    assert CTRL.next(h, float("nan"), None) == pytest.approx(0.5 * h)


def test_the_run_ends_exactly_at_t_end():
    assert CTRL.clamp_to_end(1e-3, 0.9995, 1.0) == pytest.approx(5e-4)
    assert CTRL.clamp_to_end(1e-3, 0.99896, 1.0) == pytest.approx(0.00104)  # no 40 us step
    assert CTRL.clamp_to_end(1e-3, 0.5, 1.0) == 1e-3
    t, n = 0.0, 0
    h = CTRL.first
    while not CTRL.is_last(t, 1.0):
        h = CTRL.clamp_to_end(CTRL.next(h, 0.3, 0.3), t, 1.0)
        t, n = t + h, n + 1
    assert t == pytest.approx(1.0, abs=1e-12) and n < uniform_grid_size(0.0, 1.0, 1e-4)


def test_bad_settings_are_refused():
    with pytest.raises(ValueError, match="h_min < h_max"):
        AdaptiveStep(1e-3, 1e-3, 1e-3)
    with pytest.raises(ValueError, match="both > 0"):
        AdaptiveStep(1e-4, 1e-3, 0.0)


def test_step_residual_by_hand():
    dE, carried = step_residual(np.array([110.0]), np.array([100.0]), np.array([0.5]),
                                np.array([-20.0]), np.array([-30.0]), np.array([-0.2]), 1e-3)
    assert dE == pytest.approx(0.5e-3 * (10 * 0.5 + 10 * -0.2))
    assert carried == pytest.approx(1e-3 * (50.0 + 6.0))


def test_resampled_batches_interpolate_onto_the_grid():
    t = np.array([0.0, 0.0003, 0.0004, 0.0010, 0.0013, 0.0020])
    x = 3.0 * t + 1.0  # linear: exact on the grid
    whole = next(resampled(iter([{"t": t, "x": x}]), 2e-4))
    split = list(resampled(iter([{"t": t[:3], "x": x[:3]}, {"t": t[3:], "x": x[3:]}]), 2e-4))
    grid = np.arange(11) * 2e-4
    assert np.allclose(whole["t"], grid) and np.allclose(whole["x"], 3 * grid + 1)
    got = np.concatenate([b["x"] for b in split])
    assert got.tobytes() == whole["x"].tobytes()
    assert uniform_grid_size(0.0, 0.002, 2e-4) == 11


def _rows(t, coupling_slope=0.0):
    """A bond's columns for rows at times t: a force that varies, held by the plant."""
    F = 1000.0 * np.sin(20 * t) + 2000.0
    v = 0.3 * np.cos(20 * t)
    return {"t": t, "tyre_road/force/F_t": F, "tyre_road/force/k_t": np.full(t.size, 1e5),
            "plant/state/z_w": 0.01 * np.sin(20 * t), "plant/state/v_w": v,
            "plant/state/v_b": np.zeros(t.size)}


def test_adaptive_residual_equals_the_fixed_one_on_a_uniform_grid():
    t = np.arange(400) * 1e-3
    rows = _rows(t)
    for coupling in ("hold", "linear", "jacobian"):
        fixed = ResidualStream(1e-3, coupling, "sequential")
        fixed.feed(rows)
        auto = ResidualStream(None, coupling, "sequential")
        auto.feed({k: v[:150] for k, v in rows.items()})
        auto.feed({k: v[150:] for k, v in rows.items()})
        a, b = fixed.result()["tyre"], auto.result()["tyre"]
        assert b.abs_residual == pytest.approx(a.abs_residual, rel=1e-9)
        assert b.carried == pytest.approx(a.carried, rel=1e-9)
