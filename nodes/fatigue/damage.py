"""Cycle damage and Palmgren-Miner summation per node.

Miner (thesis Eq 2.6): D = Σ n_i / N_f,i, with n_i the count of cycle i (1 or 0.5) and N_f,i
its cycles to failure from the stress-life or strain-life model with the chosen mean-stress
correction. Life (Eq 2.7) = 1 / D passes of the loaded history.
"""

from __future__ import annotations

import numpy as np

from .counting import Cycles
from .life_models import basquin_reversals, cmb_reversals, cyclic_strain, neuber, swt_reversals
from .material import Material
from .mean_stress import equivalent_amplitude

METHODS = ("stress_life", "strain_life")


def cycle_reversals(
    s1: np.ndarray,
    s2: np.ndarray,
    mat: Material,
    method: str = "stress_life",
    mean_stress: str = "goodman",
    endurance_limit: bool = False,
) -> np.ndarray:
    """Reversals to failure 2Nf of cycles between turning points s1, s2 (elastic stress, Pa).

    stress_life: σa = |s1 - s2|/2, σm = (s1 + s2)/2, σar by the mean-stress correction,
    Basquin (with Se if ``endurance_limit``).

    strain_life: Neuber converts the elastic amplitude to the local σa, εa (cyclic curve,
    Masing); the local mean follows from Neuber on the cycle's larger-magnitude extreme
    (first loading on the cyclic curve). Then CMB (none), CMB-Morrow, SWT, or for
    Goodman/Gerber the equivalent amplitude σar mapped back to εar on the cyclic curve.
    """
    s1 = np.asarray(s1, dtype=float)
    s2 = np.asarray(s2, dtype=float)
    sa_e = 0.5 * np.abs(s1 - s2)
    sm_e = 0.5 * (s1 + s2)
    if method == "stress_life":
        sar = equivalent_amplitude(sa_e, sm_e, mean_stress, mat.Su, mat.sf)
        return basquin_reversals(sar, mat.sf, mat.b, mat.Se if endurance_limit else None)
    if method != "strain_life":
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    sa = neuber(sa_e, mat)
    with np.errstate(divide="ignore", invalid="ignore"):
        ea = np.where(sa > 0, sa_e * sa_e / (mat.E * sa), 0.0)  # Neuber: σa εa = σea²/E
    peak_e = np.where(np.abs(s1) >= np.abs(s2), s1, s2)
    sign = np.where(peak_e >= 0.0, 1.0, -1.0)
    peak = sign * neuber(np.abs(peak_e), mat)
    sm = peak - sign * sa
    if mean_stress == "none":
        rev = cmb_reversals(ea, mat)
    elif mean_stress == "morrow":
        rev = cmb_reversals(ea, mat, sm)
    elif mean_stress == "swt":
        smax = sm + sa
        rev = np.where(smax > 0.0, swt_reversals(np.maximum(smax, 0.0), ea, mat), np.inf)
    else:
        sar = equivalent_amplitude(sa, sm, mean_stress, mat.Su, mat.sf)
        finite = np.isfinite(sar)
        ear = np.where(finite, cyclic_strain(np.where(finite, sar, 0.0), mat), np.inf)
        rev = np.where(finite, cmb_reversals(np.where(finite, ear, 0.0), mat), 1.0)
    if endurance_limit:
        rev = np.where(sa_e < mat.Se, np.inf, rev)
    return np.where(sa_e > 0.0, rev, np.inf)


def cycle_damage(cycles: Cycles, mat: Material, method: str, mean_stress: str,
                 endurance_limit: bool = False) -> np.ndarray:
    """Miner damage of each cycle, n / Nf (Nf = 2Nf / 2)."""
    if len(cycles) == 0:
        return np.zeros(0)
    rev = cycle_reversals(cycles.s1, cycles.s2, mat, method, mean_stress, endurance_limit)
    with np.errstate(divide="ignore"):
        return cycles.count / (0.5 * rev)


def miner_per_node(cycles: Cycles, n_nodes: int, mat: Material, method: str,
                   mean_stress: str, endurance_limit: bool = False) -> np.ndarray:
    """Palmgren-Miner damage D per node (sum of cycle damages)."""
    d = cycle_damage(cycles, mat, method, mean_stress, endurance_limit)
    return np.bincount(cycles.series, weights=d, minlength=n_nodes).astype(float)
