"""Passive dampers, the curve loader and the semi-active clipping (hand-made cases)."""

from __future__ import annotations

import numpy as np
import pytest

from cosim.errors import InputFileError
from nodes.controller.dampers import (
    PassiveCurve,
    load_curve_csv,
    passive,
    semi_active_force,
)


def test_passive_linear_sign_convention():
    # compression (wheel up toward body, v_rel > 0) pushes the body up
    assert passive(0.2, c=1500.0)[0] == pytest.approx(300.0)
    assert passive(-0.1, c=1500.0)[0] == pytest.approx(-150.0)


def test_curve_asymmetric_interpolation_and_extrapolation():
    # rebound stiffer than bump, as on a real damper
    curve = PassiveCurve([-0.5, -0.1, 0.1, 0.5], [-3000.0, -1000.0, 400.0, 1200.0])
    # origin added; bump branch slope 400/0.1 = 4000 up to 0.1, then 800/0.4 = 2000
    assert curve.force(0.05) == pytest.approx(200.0)
    assert curve.force(0.3) == pytest.approx(400.0 + 2000.0 * 0.2)
    # rebound: 1000/0.1 = 10000 N·s/m, then 2000/0.4 = 5000
    assert curve.force(-0.05) == pytest.approx(-500.0)
    assert curve.force(-0.3) == pytest.approx(-1000.0 - 5000.0 * 0.2)
    # beyond the ends: last segments extended
    assert curve.force(1.0) == pytest.approx(1200.0 + 2000.0 * 0.5)
    assert curve.force(-1.0) == pytest.approx(-3000.0 - 5000.0 * 0.5)
    np.testing.assert_allclose(curve.slope([0.05, 0.3, -0.05, -0.3]), [4000, 2000, 10000, 5000])


def test_curve_csv_with_header_and_comments(tmp_path):
    p = tmp_path / "damper.csv"
    p.write_text("# MagneShock at 0 A\nv_rel,F_d\n-0.2,-900\n\n0,0\n0.2,500\n")
    v, F = load_curve_csv(p)
    np.testing.assert_allclose(v, [-0.2, 0.0, 0.2])
    np.testing.assert_allclose(F, [-900.0, 0.0, 500.0])
    curve = PassiveCurve.from_csv(p)
    assert curve.force(0.1) == pytest.approx(250.0)
    assert curve.force(-0.1) == pytest.approx(-450.0)


@pytest.mark.parametrize(
    ("text", "line", "words"),
    [
        ("v,F\n-0.1,-100\n0.1,abc\n", 3, "not a number"),
        ("-0.1,-100\n0.2,200\n0.1,300\n", 3, "strictly increasing"),
        ("-0.1,-100\n0.1,-50\n", 2, "not dissipative"),
        ("-0.1,-100,7\n0.1,50\n", 1, "2 columns"),
        ("0.1,50\n", None, "at least 2 points"),
    ],
)
def test_curve_csv_errors_name_the_line(tmp_path, text, line, words):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(InputFileError) as err:
        load_curve_csv(p)
    assert err.value.line == line
    assert words in err.value.problem
    assert str(p) in str(err.value)


def test_curve_csv_missing_file(tmp_path):
    with pytest.raises(InputFileError, match="controller.curve: file not found"):
        load_curve_csv(tmp_path / "nope.csv")


def test_semi_active_force_clips_and_never_inputs_energy():
    v_rel = np.array([-0.2, -0.2, -0.15, 0.2, 0.0, 0.1])
    demand = np.array([-600.0, -100.0, -300.0, -300.0, 50.0, 0.0])
    F, c = semi_active_force(demand, v_rel, 1500.0, 2368.0)
    # 3000 -> c_max; 500 -> c_min; 2000 inside; wrong sign -> c_min; v=0 -> no force
    np.testing.assert_allclose(c, [2368.0, 1500.0, 2000.0, 1500.0, 1500.0, 1500.0])
    np.testing.assert_allclose(F, [-473.6, -300.0, -300.0, 300.0, 0.0, 150.0])
    assert np.all(F * v_rel >= 0.0)
