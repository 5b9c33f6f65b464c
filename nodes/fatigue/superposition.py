"""Quasi-static superposition of unit-load stresses (thesis Eq 2.8, Eq 6.1-6.6).

For every node and component c ∈ {σx, σy, σz, τxy, τyz, τzx}:
    c(t) = Σ_i c_i F_i(t),
with c_i the stress influence coefficient of load case i (Pa/N for a unit force, Pa/(N m)
for a unit moment) and F_i(t) the load history of channel i (N or N m).

**The same bits for a node whatever is computed with it.** One BLAS product of all samples
by all nodes picks its kernel (its fused multiply-adds, its summation order) by the matrices'
shapes: the same node came out up to 1.2e-7 Pa apart (1 ulp of ~4e8 Pa) computed among 113
nodes or among all 2925 (measured on the Ch 6 arm). Screening (:mod:`.screening`) computes a
changing subset of nodes that must give the unscreened result exactly, so the product is
taken per node, always of the same shape: :data:`ROWS` samples (the last chunk padded with
zero loads) by the node's (cases, 6) coefficients, a stacked ``matmul`` over the nodes. The
samples of a chunk are counted from the start of the block given: blocks must start at the
same samples for the same bits (the live node and the batch cut at the same steps).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

ROWS = 64
"""Samples per product (the fixed shape; a block's last chunk is padded with zeros)."""


def node_major(coefficients: np.ndarray) -> np.ndarray:
    """Coefficients (n_cases, n_nodes, 6) as (n_nodes, n_cases, 6), contiguous."""
    return np.ascontiguousarray(np.asarray(coefficients, dtype=float).transpose(1, 0, 2))


def _row_blocks(loads: np.ndarray, per_node: np.ndarray
                ) -> Iterator[tuple[int, int, np.ndarray]]:
    """(first row r, rows m, stresses (k, m, 6)) of ``loads`` in blocks of :data:`ROWS`: each
    block one matmul of a fixed shape (the last padded with zeros), so a node's stresses do
    not depend on which nodes or how many samples are computed with it."""
    F = np.asarray(loads, dtype=float)
    k, n_cases, n_comp = per_node.shape
    if F.ndim != 2 or F.shape[1] != n_cases:
        raise ValueError(f"loads {F.shape} and coefficients {per_node.shape} do not match")
    buf = np.zeros((1, ROWS, n_cases))
    for r in range(0, F.shape[0], ROWS):
        m = min(ROWS, F.shape[0] - r)
        buf[0, :m] = F[r:r + m]
        if m < ROWS:
            buf[0, m:] = 0.0
        yield r, m, np.matmul(buf, per_node)[:, :m]


def superpose(loads: np.ndarray, per_node: np.ndarray) -> np.ndarray:
    """Stress components (n_samples, k, 6) [Pa] of the nodes of ``per_node`` (k, n_cases, 6)
    (:func:`node_major`, any subset of nodes) under ``loads`` (n_samples, n_cases) [N, N m]."""
    k, _, n_comp = per_node.shape
    out = np.empty((np.shape(loads)[0], k, n_comp))
    for r, m, block in _row_blocks(loads, per_node):
        out[r:r + m] = block.transpose(1, 0, 2)
    return out


def superpose_components(loads: np.ndarray, per_node: np.ndarray) -> np.ndarray:
    """:func:`superpose` laid out by component first: (6, n_samples, k), each component
    contiguous (for :func:`.equivalent_stress.equivalent_of`); the same values."""
    k, _, n_comp = per_node.shape
    out = np.empty((n_comp, np.shape(loads)[0], k))
    for r, m, block in _row_blocks(loads, per_node):
        out[:, r:r + m] = block.transpose(2, 1, 0)
    return out


def stress_history(loads: np.ndarray, coefficients: np.ndarray) -> np.ndarray:
    """Stress components of every node over time.

    Args:
        loads: (n_samples, n_cases) load histories F_i(t), columns in case order.
        coefficients: (n_cases, n_nodes, 6) influence coefficients c_i.

    Returns:
        (n_samples, n_nodes, 6) stresses in Pa (:func:`superpose`, per node).
    """
    F = np.asarray(loads, dtype=float)
    C = np.asarray(coefficients, dtype=float)
    if F.ndim != 2 or C.ndim != 3 or F.shape[1] != C.shape[0]:
        raise ValueError(f"loads {F.shape} and coefficients {C.shape} do not match")
    return superpose(F, node_major(C))
