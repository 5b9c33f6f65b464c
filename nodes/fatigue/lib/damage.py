"""Cycle damage and Palmgren-Miner summation per node; a law's damage per unit of range.

Miner (thesis Eq 2.6): D = Σ n_i / N_f,i, with n_i the count of cycle i (1 or 0.5) and N_f,i
its cycles to failure from the stress-life or strain-life model with the chosen mean-stress
correction. Life (Eq 2.7) = 1 / D passes of the loaded history.

**Endurance limit: one rule for both methods.** A cycle's *equivalent fully reversed amplitude*
σar (its amplitude corrected for its mean by the chosen mean-stress correction, Pa) is compared
with the endurance limit Se of the S-N curve in use (``mat.sn``, the component curve, or the
material's). σar is computed from the stresses the method works with: the elastic (FE) amplitude
and mean in stress-life, the local Neuber amplitude and mean in strain-life (the two are equal
below the cyclic yield stress, where Se lies). Below Se the treatment is the curve's
``endurance`` (or the ``endurance_limit`` argument): "elementary" Miner (no damage), "haibach"
(modified Miner, slope k' = 2k - 1 below the knee: N = N_D (Se/σar)^(2k-1), N_D the method's own
life at σar = Se, k = -1/b) or "none" (the curve continued). SWT's σar is sqrt(σmax σa); with
"none" as the correction σar = σa.
"""

from __future__ import annotations

import numpy as np

from .counting import Cycles
from .life_models import (
    ENDURANCE_MODES,
    SNCurve,
    below_knee,
    cmb_reversals,
    cyclic_strain,
    neuber,
    swt_reversals,
)
from .material import Material, material_sn_curve
from .mean_stress import equivalent_amplitude
from .sn_data import TabulatedSN

TIME_METHODS = ("stress_life", "strain_life")
"""The rainflow methods (this module); the spectral ones (:mod:`.spectral`: the PSD of the
whole history, after a run: ``suscosim fatigue RUN``) take the stress-life curve."""
SPECTRAL_METHODS = ("dirlik", "tovo_benasciutti")
GRID = 8
"""Amplitude intervals of :func:`damage_per_range`'s bound."""
METHODS = TIME_METHODS + SPECTRAL_METHODS


def _endurance(curve: SNCurve | TabulatedSN, endurance_limit: str | None) -> str:
    """The endurance treatment: the curve's, or the argument's (a mode name)."""
    if endurance_limit is None:
        return curve.endurance
    if endurance_limit not in ENDURANCE_MODES:
        raise ValueError(f"endurance_limit must be one of {ENDURANCE_MODES}, "
                         f"got {endurance_limit!r}")
    return endurance_limit


def sn_curve(mat: Material) -> SNCurve | TabulatedSN:
    """The S-N curve damage uses for ``mat``: ``mat.sn`` or the material's Basquin line."""
    return mat.sn if mat.sn is not None else material_sn_curve(mat)


def cycle_reversals(
    s1: np.ndarray,
    s2: np.ndarray,
    mat: Material,
    method: str = "stress_life",
    mean_stress: str = "goodman",
    endurance_limit: str | None = None,
) -> np.ndarray:
    """Reversals to failure 2Nf of cycles between turning points s1, s2 (elastic stress, Pa).

    stress_life: σa = |s1 - s2|/2, σm = (s1 + s2)/2, σar by the mean-stress correction, then
    the S-N curve (`sn_curve`: the component curve ``mat.sn`` if attached, else the material's
    Basquin line).

    strain_life: Neuber converts the elastic amplitude to the local σa, εa (cyclic curve,
    Masing); the local mean follows from Neuber on the cycle's larger-magnitude extreme
    (first loading on the cyclic curve). Then CMB (none), CMB-Morrow, SWT, or for
    Goodman/Gerber the equivalent amplitude σar mapped back to εar on the cyclic curve. The
    strain-life constants are the material's (σ'f, b, ε'f, c, K', n').

    Both: the endurance rule of the module docstring, with Se of `sn_curve` (``endurance_limit``
    None = the curve's own treatment).
    """
    s1 = np.asarray(s1, dtype=float)
    s2 = np.asarray(s2, dtype=float)
    curve = sn_curve(mat)
    mode = _endurance(curve, endurance_limit)
    sa_e = 0.5 * np.abs(s1 - s2)
    sm_e = 0.5 * (s1 + s2)
    M = (curve.meta or {}).get("mean_stress_sensitivity")
    if method == "stress_life":
        sar = equivalent_amplitude(sa_e, sm_e, mean_stress, mat.Su, mat.sf, M)
        return curve.with_endurance(mode).reversals(sar)
    if method != "strain_life":
        raise ValueError(f"method must be one of {TIME_METHODS}, got {method!r}")
    sa = neuber(sa_e, mat)
    with np.errstate(divide="ignore", invalid="ignore"):
        ea = np.where(sa > 0, sa_e * sa_e / (mat.E * sa), 0.0)  # Neuber: σa εa = σea²/E
    peak_e = np.where(np.abs(s1) >= np.abs(s2), s1, s2)
    sign = np.where(peak_e >= 0.0, 1.0, -1.0)
    peak = sign * neuber(np.abs(peak_e), mat)
    sm = peak - sign * sa
    sar = equivalent_amplitude(sa, sm, mean_stress, mat.Su, mat.sf, M)
    if mean_stress == "none":
        rev = cmb_reversals(ea, mat)
    elif mean_stress == "morrow":
        rev = cmb_reversals(ea, mat, sm)
    elif mean_stress == "swt":
        smax = sm + sa
        rev = np.where(smax > 0.0, swt_reversals(np.maximum(smax, 0.0), ea, mat), np.inf)
    else:
        finite = np.isfinite(sar)
        ear = np.where(finite, cyclic_strain(np.where(finite, sar, 0.0), mat), np.inf)
        rev = np.where(finite, cmb_reversals(np.where(finite, ear, 0.0), mat), 1.0)
    if mode != "none":
        rev = below_knee(rev, sar, curve.Se, strain_life_knee(curve.Se, mat, mean_stress),
                         -1.0 / mat.b, mode)
    return np.where(sa_e > 0.0, rev, np.inf)


def strain_life_knee(Se: float, mat: Material, mean_stress: str) -> float:
    """2N_D of strain-life at the knee: the method's life of a fully reversed cycle whose local
    amplitude is Se (Pa) (SWT's equation for "swt", Coffin-Manson-Basquin otherwise)."""
    e = cyclic_strain(np.array([Se]), mat)
    if mean_stress == "swt":
        return float(swt_reversals(np.array([Se]), e, mat)[0])
    return float(cmb_reversals(e, mat)[0])


def cycle_damage(cycles: Cycles, mat: Material, method: str, mean_stress: str,
                 endurance_limit: str | None = None) -> np.ndarray:
    """Miner damage of each cycle, n / Nf (Nf = 2Nf / 2)."""
    if len(cycles) == 0:
        return np.zeros(0)
    rev = cycle_reversals(cycles.s1, cycles.s2, mat, method, mean_stress, endurance_limit)
    with np.errstate(divide="ignore"):
        return cycles.count / (0.5 * rev)


def per_range_unsupported(mat: Material, method: str, mean_stress: str) -> str | None:
    """Why :func:`damage_per_range` is no proven bound for these settings (None: it is, and
    :mod:`.screening` may run): stress-life, a mean-stress correction linear in σa at a given
    σm (or SWT), S-N slopes k >= 1 (2 for SWT) on every segment, so that a cycle's damage per
    unit of range grows with its range (docs/live_fatigue.md, "The screening bound")."""
    if method != "stress_life":
        return f"method {method!r} (the bound is proven for stress_life)"
    if mean_stress not in ("none", "goodman", "gerber", "morrow", "swt"):
        return f"mean_stress {mean_stress!r} (the bound is proven for none, goodman, " \
               "gerber, morrow, swt)"
    curve = sn_curve(mat)
    if isinstance(curve, SNCurve):
        slopes = [curve.k]
        if curve.lcf_Su is not None:
            b_lcf = np.log(curve.lcf_stress / curve.lcf_Su) / np.log(curve.lcf_reversals / 2.0)
            slopes.append(-1.0 / b_lcf)
    elif hasattr(curve, "n_cycles") and hasattr(curve, "s_amp"):  # a tabulated curve
        logn, logs = np.log(np.asarray(curve.n_cycles)), np.log(np.asarray(curve.s_amp))
        slopes = list(-np.diff(logn) / np.diff(logs))
        tail = getattr(curve, "tail_b", None)
        if tail is not None and tail < 0.0:
            slopes.append(-1.0 / tail)
    else:
        return f"an S-N curve of type {type(curve).__name__}"
    need = 2.0 if mean_stress == "swt" else 1.0
    if min(slopes) < need:
        return f"an S-N slope k = {min(slopes):.3g} < {need:g} (damage per range must grow)"
    return None


def damage_per_range(hi: np.ndarray, lo: np.ndarray, mat: Material, method: str,
                     mean_stress: str, endurance: str | None) -> np.ndarray:
    """g (1/Pa): every cycle with both extremes in [lo, hi] (Pa) has damage <= g · its range."""
    hi = np.asarray(hi, dtype=float)
    lo = np.asarray(lo, dtype=float)
    A = np.maximum(0.5 * (hi - lo), 0.0)
    j = np.arange(GRID, dtype=float)
    a0 = A[:, None] * (j / GRID)
    a1 = A[:, None] * ((j + 1.0) / GRID)
    m = hi[:, None] - a0
    finite = np.isfinite(a1) & np.isfinite(m)
    a1f, mf = np.where(finite, a1, 0.0), np.where(finite, m, 0.0)
    rev = cycle_reversals(mf + a1f, mf - a1f, mat, method, mean_stress, endurance)
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.where(a1f > 0.0, (2.0 / rev) / (2.0 * a1f), 0.0)
    g = np.where(finite, g, np.inf)
    return g.max(axis=1) if g.size else np.zeros(hi.shape)
