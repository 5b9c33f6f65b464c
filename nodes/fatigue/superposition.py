"""Quasi-static superposition of unit-load stresses (thesis Eq 2.8, Eq 6.1-6.6).

For every node and component c ∈ {σx, σy, σz, τxy, τyz, τzx}:
    c(t) = Σ_i c_i F_i(t),
with c_i the stress influence coefficient of load case i (Pa/N for a unit force, Pa/(N m)
for a unit moment) and F_i(t) the load history of channel i (N or N m).
"""

from __future__ import annotations

import numpy as np


def stress_history(loads: np.ndarray, coefficients: np.ndarray) -> np.ndarray:
    """Stress components of every node over time.

    Args:
        loads: (n_samples, n_cases) load histories F_i(t), columns in case order.
        coefficients: (n_cases, n_nodes, 6) influence coefficients c_i.

    Returns:
        (n_samples, n_nodes, 6) stresses in Pa. One matrix product (BLAS).
    """
    F = np.asarray(loads, dtype=float)
    C = np.asarray(coefficients, dtype=float)
    if F.ndim != 2 or C.ndim != 3 or F.shape[1] != C.shape[0]:
        raise ValueError(f"loads {F.shape} and coefficients {C.shape} do not match")
    n_cases, n_nodes, n_comp = C.shape
    return (F @ C.reshape(n_cases, n_nodes * n_comp)).reshape(F.shape[0], n_nodes, n_comp)
