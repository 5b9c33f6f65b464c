"""Equivalent stresses and superposition against hand values."""

from __future__ import annotations

import numpy as np

from nodes.fatigue.lib.equivalent_stress import (
    abs_max_principal,
    principal_extremes,
    signed_von_mises,
    von_mises,
)
from nodes.fatigue.lib.superposition import stress_history


def _tensor(s):
    sx, sy, sz, txy, tyz, tzx = s
    return np.array([[sx, txy, tzx], [txy, sy, tyz], [tzx, tyz, sz]])


def test_principal_matches_eigvalsh():
    rng = np.random.default_rng(0)
    s = rng.normal(size=(500, 6)) * 1e8
    s[0] = [1e8, 0, 0, 0, 0, 0]
    s[1] = [5e7, 5e7, 5e7, 0, 0, 0]  # hydrostatic: p = 0
    s1, s3 = principal_extremes(s)
    ev = np.array([np.linalg.eigvalsh(_tensor(r)) for r in s])
    np.testing.assert_allclose(s1, ev[:, 2], atol=1e-3)
    np.testing.assert_allclose(s3, ev[:, 0], atol=1e-3)
    amp = abs_max_principal(s)
    ref = np.where(np.abs(ev[:, 2]) >= np.abs(ev[:, 0]), ev[:, 2], ev[:, 0])
    np.testing.assert_allclose(amp, ref, atol=1e-3)


def test_von_mises_hand_values():
    assert von_mises(np.array([100.0, 0, 0, 0, 0, 0])) == 100.0
    assert np.isclose(von_mises(np.array([0, 0, 0, 10.0, 0, 0])), 10 * np.sqrt(3))
    assert signed_von_mises(np.array([-100.0, 0, 0, 0, 0, 0])) == -100.0


def test_superposition_is_linear_combination():
    rng = np.random.default_rng(1)
    C = rng.normal(size=(3, 5, 6))
    F = rng.normal(size=(7, 3))
    S = stress_history(F, C)
    ref = np.einsum("ti,inc->tnc", F, C)
    np.testing.assert_allclose(S, ref)
