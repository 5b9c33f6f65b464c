"""The superposition is the plain sum in case order (no fused multiply-add): the compiled
kernel gives its bits (against the sum in Python floats), for any subset of nodes and any
length, with NaN and inf too."""

from __future__ import annotations

import numpy as np
import pytest

from nodes.fatigue.lib.equivalent_stress import equivalent_of
from nodes.fatigue.lib.superposition import superpose, superpose_components


def _reference(F: np.ndarray, per_node: np.ndarray) -> np.ndarray:
    """(n, k, 6): per sample and node, sum_c (coefficient_c x load_c) in case order, each
    product rounded then added (Python floats: IEEE double, no fused multiply-add)."""
    n, k = F.shape[0], per_node.shape[0]
    out = np.empty((n, k, 6))
    for s in range(n):
        for i in range(k):
            for m in range(6):
                acc = float(per_node[i, 0, m]) * float(F[s, 0])
                for c in range(1, F.shape[1]):
                    acc = acc + float(per_node[i, c, m]) * float(F[s, c])
                out[s, i, m] = acc
    return out


@pytest.mark.parametrize("cases", [1, 3, 4, 7, 15])
def test_the_sum_in_case_order_any_subset_any_length(cases) -> None:
    rng = np.random.default_rng(7 + cases)
    per_node = rng.normal(size=(40, cases, 6)) * 1e4
    per_node[0, 0] = -0.0  # a signed zero stays signed
    for n in (1, 37, 64, 65, 130):
        F = rng.normal(size=(n, cases)) * 1e3
        ref = _reference(F, per_node)
        got = superpose(F, per_node)
        assert np.array_equal(got.view(np.int64), ref.view(np.int64))
        comp = superpose_components(F, per_node)
        assert comp.shape == (6, n, 40)
        assert np.array_equal(comp, ref.transpose(2, 0, 1))
        sub = np.sort(rng.choice(40, 17, replace=False))
        assert np.array_equal(superpose_components(F, per_node[sub]), comp[:, :, sub])


def test_the_sum_in_case_order_with_nan_and_inf() -> None:
    rng = np.random.default_rng(11)
    per_node = rng.normal(size=(9, 15, 6)) * 1e4
    F = rng.normal(size=(70, 15)) * 1e3
    F[3, 0], F[4, 14], F[5, 2] = np.inf, np.nan, 0.0
    F[6, 1] = -np.inf
    got = superpose(F, per_node)
    assert np.isnan(got).any() and np.isinf(got).any()
    assert np.array_equal(got, _reference(F, per_node), equal_nan=True)


def test_coefficients_not_six_components_are_refused() -> None:
    with pytest.raises(ValueError, match="do not match"):
        superpose(np.zeros((4, 3)), np.zeros((2, 3, 5)))


def test_equivalent_of_a_view_equals_contiguous() -> None:
    rng = np.random.default_rng(3)
    F = rng.normal(size=(100, 15)) * 1e3
    comp = superpose_components(F, rng.normal(size=(50, 15, 6)) * 1e4)
    for kind in ("abs_max_principal", "signed_von_mises"):
        assert np.array_equal(equivalent_of(comp, kind),
                              equivalent_of(np.ascontiguousarray(comp), kind))
