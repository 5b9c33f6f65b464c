"""The fast superposition layout gives the bits of the per-node fixed-shape product."""

from __future__ import annotations

import numpy as np

from nodes.fatigue.equivalent_stress import equivalent_of
from nodes.fatigue.superposition import ROWS, superpose, superpose_components


def _reference(F: np.ndarray, per_node: np.ndarray) -> np.ndarray:
    """(n, k, 6): the (ROWS, cases) x (cases, 6) product per node, last chunk zero-padded."""
    out = []
    for r in range(0, F.shape[0], ROWS):
        m = min(ROWS, F.shape[0] - r)
        buf = np.zeros((1, ROWS, F.shape[1]))
        buf[0, :m] = F[r:r + m]
        out.append(np.matmul(buf, per_node)[:, :m].transpose(1, 0, 2))
    return np.concatenate(out, axis=0)


def test_same_bits_as_per_node_product_any_subset_any_length() -> None:
    rng = np.random.default_rng(7)
    per_node = rng.normal(size=(300, 15, 6)) * 1e4
    for n in (1, 37, 64, 65, 500):
        F = rng.normal(size=(n, 15)) * 1e3
        ref = _reference(F, per_node)
        assert np.array_equal(superpose(F, per_node), ref)
        comp = superpose_components(F, per_node)
        assert comp.shape == (6, n, 300)
        assert np.array_equal(comp, ref.transpose(2, 0, 1))
        sub = np.sort(rng.choice(300, 17, replace=False))
        assert np.array_equal(superpose_components(F, per_node[sub]), comp[:, :, sub])


def test_equivalent_of_a_view_equals_contiguous() -> None:
    rng = np.random.default_rng(3)
    F = rng.normal(size=(100, 15)) * 1e3
    comp = superpose_components(F, rng.normal(size=(50, 15, 6)) * 1e4)
    for kind in ("abs_max_principal", "signed_von_mises"):
        assert np.array_equal(equivalent_of(comp, kind),
                              equivalent_of(np.ascontiguousarray(comp), kind))
