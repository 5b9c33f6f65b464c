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

import numpy as np

ROWS = 64
"""Samples per product (the fixed shape; a block's last chunk is padded with zeros)."""


def node_major(coefficients: np.ndarray) -> np.ndarray:
    """Coefficients (n_cases, n_nodes, 6) as (n_nodes, n_cases, 6), contiguous."""
    return np.ascontiguousarray(np.asarray(coefficients, dtype=float).transpose(1, 0, 2))


def _products(loads: np.ndarray, per_node: np.ndarray, scratch: np.ndarray | None = None
              ) -> tuple[np.ndarray, int]:
    """Stresses (6, k, n_pad) [Pa] of ``loads`` (n, n_cases) [N, N m] in chunks of
    :data:`ROWS` samples (the last padded with zero loads), and n. Each chunk is one stacked
    ``matmul`` of a fixed shape, the node's (6, n_cases) coefficients by the chunk's
    (n_cases, ROWS) loads: the same bits as the (ROWS, n_cases) x (n_cases, 6) product per
    node (checked over every chunk of the Ch 6 run and by ``tests/fatigue``), written straight
    into a buffer laid out (component, node, sample), so no transposing copy follows (it
    cost 3/4 of the time) and each component is contiguous. ``scratch``: a flat float64
    array of at least 6 k n_pad elements to write into (a fresh one otherwise)."""
    F = np.asarray(loads, dtype=float)
    k, n_cases, n_comp = per_node.shape
    if F.ndim != 2 or F.shape[1] != n_cases:
        raise ValueError(f"loads {F.shape} and coefficients {per_node.shape} do not match")
    n = F.shape[0]
    chunks = max(1, -(-n // ROWS))
    FT = np.zeros((chunks, n_cases, ROWS))
    for c in range(chunks):
        m = min(ROWS, n - c * ROWS)
        if m > 0:
            FT[c, :, :m] = F[c * ROWS:c * ROWS + m].T
    coef_t = per_node.transpose(0, 2, 1)  # (k, 6, n_cases), a view
    shape = (n_comp, k, chunks, ROWS)
    size = n_comp * k * chunks * ROWS
    out = np.empty(shape) if scratch is None else scratch[:size].reshape(shape)
    by_node = out.transpose(1, 0, 2, 3)
    for c in range(chunks):
        np.matmul(coef_t, FT[c], out=by_node[:, :, c, :])
    return out.reshape(n_comp, k, chunks * ROWS), n


def components_buffer(loads: np.ndarray, per_node: np.ndarray,
                      scratch: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """The products themselves: a C-contiguous (6, k, n_pad) buffer (component, node, sample;
    n_pad = n rounded up to :data:`ROWS`, the padding the stresses of zero loads) and n.
    :func:`superpose_components` is ``buf.transpose(0, 2, 1)[:, :n]``: the same bits.
    ``scratch``: written into (a flat float64 array of >= 6 k n_pad; reused, it saves the
    page faults of a fresh 4 MB buffer per tile)."""
    if scratch is not None and (scratch.dtype != np.float64 or scratch.ndim != 1
                                or not scratch.flags.c_contiguous):
        raise ValueError("scratch must be a flat, contiguous float64 array")
    return _products(loads, per_node, scratch)


def superpose(loads: np.ndarray, per_node: np.ndarray) -> np.ndarray:
    """Stress components (n_samples, k, 6) [Pa] of the nodes of ``per_node`` (k, n_cases, 6)
    (:func:`node_major`, any subset of nodes) under ``loads`` (n_samples, n_cases) [N, N m]."""
    out, n = _products(loads, per_node)
    return np.ascontiguousarray(out.transpose(2, 1, 0)[:n])


def superpose_components(loads: np.ndarray, per_node: np.ndarray) -> np.ndarray:
    """:func:`superpose` laid out by component first: (6, n_samples, k), the same values.
    A view of a (component, node, sample) buffer: ``.transpose(0, 2, 1)`` of it is each
    component contiguous, node-major (:func:`.equivalent_stress.equivalent_of` works there)."""
    out, n = _products(loads, per_node)
    return out.transpose(0, 2, 1)[:, :n]


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
