"""The acceleration-driven damper (ADD): switching on a_b * v_rel, acceleration from v_b."""

from __future__ import annotations

import numpy as np
import pytest

from nodes.controller.laws import build_controller


def state(v_b, v_w):
    return {"z_b": np.zeros(2), "z_w": np.zeros(2), "v_b": np.array(v_b, dtype=float),
            "v_w": np.array(v_w, dtype=float)}


def test_add_is_hard_where_the_damper_force_opposes_the_body_acceleration():
    ctl = build_controller({"law": "add"}, 2, 0.001)
    first = ctl.step(0.0, state([0.0, 0.0], [0.1, 0.1]))
    np.testing.assert_array_equal(first.extra["state"], [0.0, 0.0])  # no acceleration yet: soft
    # corner 0: body accelerating up (+1 m/s² over 1 ms), damper compressing (v_rel = +0.099):
    #   c v_rel pushes the body up, with the acceleration -> soft, F = 1500 * 0.099
    # corner 1: body accelerating down, damper compressing (v_rel = +0.101) -> hard
    out = ctl.step(0.001, state([0.001, -0.001], [0.1, 0.1]))
    np.testing.assert_allclose(out.extra["a_b_est"], [1.0, -1.0])
    np.testing.assert_array_equal(out.extra["state"], [0.0, 1.0])
    np.testing.assert_allclose(out.F_d, [1500.0 * 0.099, 2368.0 * 0.101])
    np.testing.assert_allclose(out.c_eff, [1500.0, 2368.0])


def test_add_takes_the_realistic_preset_and_refuses_hard_below_soft():
    ctl = build_controller({"law": "add", "preset": "realistic"}, 2, 0.001)
    ctl.step(0.0, state([0.0, 0.0], [0.0, 0.0]))
    out = ctl.step(0.001, state([-0.001, -0.001], [0.1, 0.1]))
    assert out.c_eff.tolist() == [6000.0, 6000.0]
    with pytest.raises(ValueError, match="controller.c_hard"):
        build_controller({"law": "add", "c_soft": 3000.0, "c_hard": 2000.0}, 1, 0.001)
