"""Issue #31 item 1: the Magic Formula 6.1 tyre (nodes/tyre_road/magic_formula.py) against an
independent implementation and hand-computed points.

``mfeval_mpv_215_65r16.csv`` holds the outputs of MFeval (Marco Furlan's open MATLAB
implementation of MF 5.2/6.1/6.2, which its author matched against TNO's MF-Tyre), run under
GNU Octave 7.3 with use mode 111 (limits checked, no alpha*, no turn slip) on the shipped
``nodes/tyre_road/tyres/mpv_215_65r16.tir``; docs/tyres.md gives the commands. The points:
Fx(kappa) and Fy(alpha), Mz(alpha) at 3000, 5000, 8000 N; a kappa x alpha grid; camber +-0.05
rad; two pressures other than the nominal.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest

from cosim.errors import InputFileError
from nodes.tyre_road.magic_formula import BUILTIN, MagicFormula, parse_tir, read_tir, relax

REF = Path(__file__).with_name("mfeval_mpv_215_65r16.csv")
TOL = 1e-4
"""Relative to the larger of |reference| and 1 % of the curve's largest value (the brief asks
for 1 %; measured: 1.3e-7 on Mz, below 1e-9 on the forces)."""


@pytest.fixture(scope="module")
def tyre() -> MagicFormula:
    return MagicFormula.from_tir()


@pytest.fixture(scope="module")
def ref() -> dict[str, np.ndarray]:
    with REF.open() as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def _ours(tyre: MagicFormula, ref: dict[str, np.ndarray], sel: np.ndarray):
    return tyre.steady_state(ref["Fz"][sel], ref["kappa"][sel], ref["alpha"][sel],
                             ref["gamma"][sel], ref["Vx"][sel], ref["p"][sel])


def _assert_close(ours: np.ndarray, theirs: np.ndarray, what: str) -> None:
    scale = np.maximum(np.abs(theirs), 0.01 * np.abs(theirs).max())
    worst = float(np.max(np.abs(ours - theirs) / scale))
    assert worst < TOL, f"{what}: {worst:.2e} off MFeval"


def test_pure_longitudinal_fx_of_kappa(tyre, ref) -> None:
    sel = (ref["alpha"] == 0) & (ref["gamma"] == 0) & (ref["kappa"] != 0)
    assert sel.sum() >= 36  # 12 slips x 3 loads
    r = _ours(tyre, ref, sel)
    for fz in (3000.0, 5000.0, 8000.0):
        at = ref["Fz"][sel] == fz
        _assert_close(r["Fx"][at], ref["Fx"][sel][at], f"Fx(kappa) at {fz:g} N")
    _assert_close(r["Kxk"], ref["Kxk"][sel], "Kxk")


def test_pure_lateral_fy_and_mz_of_alpha(tyre, ref) -> None:
    sel = (ref["kappa"] == 0) & (ref["gamma"] == 0)
    assert sel.sum() >= 33
    r = _ours(tyre, ref, sel)
    for fz in (3000.0, 5000.0, 8000.0):
        at = ref["Fz"][sel] == fz
        _assert_close(r["Fy"][at], ref["Fy"][sel][at], f"Fy(alpha) at {fz:g} N")
        _assert_close(r["Mz"][at], ref["Mz"][sel][at], f"Mz(alpha) at {fz:g} N")
    _assert_close(r["Kya"], ref["Kya"][sel], "Kya")


def test_combined_slip_camber_pressure_and_relaxation_lengths(tyre, ref) -> None:
    sel = (ref["kappa"] != 0) & (ref["alpha"] != 0) | (ref["gamma"] != 0) \
        | (ref["p"] != 250000.0)
    assert sel.sum() >= 24
    r = _ours(tyre, ref, sel)
    for key in ("Fx", "Fy", "Mz"):
        _assert_close(r[key], ref[key][sel], f"combined {key}")
    everything = np.ones(len(ref["Fz"]), bool)
    r = _ours(tyre, ref, everything)
    for key in ("sigma_x", "sigma_y", "t", "Mzr"):
        _assert_close(r[key], ref[key], key)


def test_hand_computed_points(tyre) -> None:
    """At the rated load (dfz = 0, dpi = 0) the stiffnesses and the peak are the .tir's
    coefficients: Kxk = PKX1 Fz (Eq. 4.E15), Kya = PKY1 Fz0 sin(PKY4 atan(1 / PKY2)) (4.E25),
    the peak of Fx0 = D + SVx = PDX1 Fz + PVX1 Fz (4.E11-4.E18, C > 1), and
    sigma_y = |Kya| / LATERAL_STIFFNESS."""
    r = tyre.steady_state(5000.0, 0.0, 0.0)
    assert float(r["Kxk"]) == pytest.approx(22.0 * 5000.0, rel=1e-12)
    kya = -16.0 * 5000.0 * math.sin(2.0 * math.atan(1.0 / 1.8))  # -67924.5 N/rad
    assert float(r["Kya"]) == pytest.approx(kya, rel=1e-12)
    assert float(r["sigma_y"]) == pytest.approx(abs(kya) / 170000.0, rel=1e-12)
    kappa = np.linspace(0.0, 0.5, 50001)
    fx = tyre.steady_state(5000.0, kappa, 0.0)["Fx"]
    assert float(fx.max()) == pytest.approx(1.15 * 5000.0 + 0.00002 * 5000.0, rel=1e-6)
    # the slope at zero slip is Kxk (the small horizontal shift SHx moves the origin)
    d = 1e-7
    shx = 0.0005
    slope = (tyre.steady_state(5000.0, -shx + d, 0.0)["Fx"]
             - tyre.steady_state(5000.0, -shx - d, 0.0)["Fx"]) / (2 * d)
    assert float(slope) == pytest.approx(22.0 * 5000.0, rel=1e-6)


def test_relaxation_is_a_first_order_lag_over_distance() -> None:
    """sigma d(alpha')/ds + alpha' = alpha: after one relaxation length 1 - 1/e of a step,
    the same whatever the step size, and the kinematic slip in steady state."""
    sigma, v = 0.4, 20.0
    coarse = relax(0.0, 0.1, v, sigma, sigma / v)  # one step of one relaxation length
    a = 0.0
    for _ in range(1000):
        a = float(relax(a, 0.1, v, sigma, sigma / v / 1000))
    assert float(coarse) == pytest.approx(0.1 * (1 - math.exp(-1)), rel=1e-12)
    assert a == pytest.approx(float(coarse), rel=1e-9)
    assert float(relax(0.05, 0.1, v, sigma, 10.0)) == pytest.approx(0.1)
    assert float(relax(0.05, 0.1, 0.0, sigma, 1.0)) == 0.05  # standing still: no change


def test_the_tir_reader_names_the_file_and_line(tmp_path) -> None:
    raw = read_tir(BUILTIN)
    assert raw["UNITS/MASS"] == "kg" and raw["INERTIA/MASS"] == 11.0 and raw["FITTYP"] == 61
    assert parse_tir("[A]\nX = 1.5E-3 $ comment\nNAME = 'a $ b' ! c\n") == {
        "A/X": 1.5e-3, "X": 1.5e-3, "A/NAME": "a $ b", "NAME": "a $ b"}
    with pytest.raises(InputFileError, match=r"t.tir:3: expected KEY = VALUE"):
        parse_tir("[A]\nX = 1\nthis is not a key\n", "t.tir")
    with pytest.raises(InputFileError, match=r":3: key X given twice in \[A\]"):
        parse_tir("[A]\nX = 1\nX = 2\n", "t.tir")
    with pytest.raises(InputFileError, match="X: expected a number"):
        parse_tir("[A]\nX = 1,5\n", "t.tir")
    old = tmp_path / "mf52.tir"
    old.write_text("[MODEL]\nFITTYP = 6\n")
    with pytest.raises(InputFileError, match="FITTYP = 6.0: only Magic Formula 6.1"):
        MagicFormula.from_tir(old)
    part = tmp_path / "part.tir"
    part.write_text("[MODEL]\nFITTYP = 61\n[VERTICAL]\nFNOMIN = 4000\n")
    with pytest.raises(InputFileError, match="no UNLOADED_RADIUS"):
        MagicFormula.from_tir(part)
