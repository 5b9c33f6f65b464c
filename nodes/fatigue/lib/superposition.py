"""Quasi-static superposition of unit-load stresses (thesis Eq 2.8, Eq 6.1-6.6).

For every node and component c ∈ {σx, σy, σz, τxy, τyz, τzx}:
    c(t) = Σ_i c_i F_i(t),
with c_i the stress influence coefficient of load case i (Pa/N for a unit force, Pa/(N m)
for a unit moment) and F_i(t) the load history of channel i (N or N m).

**The same bits for a node whatever is computed with it.** A BLAS product picks its kernel
(fused multiply-adds, summation order) by the matrices' shapes, so a node's stress would depend
on the node set (up to 1 ulp, 1.2e-7 Pa of ~4e8 Pa, on the Ch 6 arm). Screening
(:mod:`.screening`) computes a changing subset of nodes that must give the unscreened result
exactly, so each component is *defined* as the plain sum in case order, every product rounded,
no fused multiply-add: ``c = ((c_0 F_0 + c_1 F_1) + c_2 F_2) + ...`` per sample and node. The
compiled kernel (numba, :func:`.turning_eq.products_compiled`: the loads of four cases at a
time in registers, each sample's six components summed in that order; the live engine fuses it
per node with the turning-point gather, :func:`.turning_eq.superpose_gather`) gives those bits
(``tests/fatigue/test_superposition_fast.py`` checks them against the sum in Python floats),
for any subset of nodes and any cut of the history (each sample is computed alone).
"""

from __future__ import annotations

import numpy as np

ROWS = 64
"""The buffers' sample axis is padded to a multiple of this (zero loads: zero stresses)."""


def node_major(coefficients: np.ndarray) -> np.ndarray:
    """Coefficients (n_cases, n_nodes, 6) as (n_nodes, n_cases, 6), contiguous."""
    return np.ascontiguousarray(np.asarray(coefficients, dtype=float).transpose(1, 0, 2))


def build() -> None:
    """Compile the product kernel now (or load it from numba's cache; once):
    :func:`.turning_eq.build`, where it lives beside the kernels it is fused with."""
    from . import turning_eq

    turning_eq.build()


def _products(loads: np.ndarray, per_node: np.ndarray, scratch: np.ndarray | None = None
              ) -> tuple[np.ndarray, int]:
    """Stresses (6, k, n_pad) [Pa] of ``loads`` (n, n_cases) [N, N m] for the nodes
    ``per_node`` (k, n_cases, 6): per sample the sum in case order (module docstring),
    laid out (component, node, sample) so each component is contiguous; the padding up to
    a multiple of :data:`ROWS` samples is the stresses of zero loads. Returns it and n.
    ``scratch``: a flat float64 array of at least 6 k n_pad elements to write into (a fresh
    one otherwise)."""
    F = np.asarray(loads, dtype=float)
    k, n_cases, n_comp = per_node.shape
    if F.ndim != 2 or F.shape[1] != n_cases or n_comp != 6:
        raise ValueError(f"loads {F.shape} and coefficients {per_node.shape} do not match")
    n = F.shape[0]
    n_pad = max(1, -(-n // ROWS)) * ROWS
    FT = np.zeros((n_cases, n_pad))
    FT[:, :n] = F.T
    shape = (n_comp, k, n_pad)
    size = n_comp * k * n_pad
    out = np.empty(shape) if scratch is None else scratch[:size].reshape(shape)
    coef = np.ascontiguousarray(per_node, dtype=float)
    from .turning_eq import products_compiled

    products_compiled(FT, coef, out)
    return out, n


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
    """Stresses (n_samples, n_nodes, 6) [Pa] of every node over time from the load
    histories F_i(t) (n_samples, n_cases), columns in case order, and the influence
    coefficients c_i (n_cases, n_nodes, 6) (:func:`superpose`, per node)."""
    F = np.asarray(loads, dtype=float)
    C = np.asarray(coefficients, dtype=float)
    if F.ndim != 2 or C.ndim != 3 or F.shape[1] != C.shape[0]:
        raise ValueError(f"loads {F.shape} and coefficients {C.shape} do not match")
    return superpose(F, node_major(C))
