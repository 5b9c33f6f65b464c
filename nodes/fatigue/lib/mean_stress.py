"""Mean-stress corrections: equivalent fully reversed stress amplitude σar (Pa).

Each takes the cycle's stress amplitude σa and mean σm (Pa) and returns the amplitude that
would do the same damage at zero mean:

* Goodman:  σar = σa / (1 - σm/σu)          (applied to compressive means too: beneficial)
* Gerber:   σar = σa / (1 - (σm/σu)^2)      for σm > 0; no correction for σm <= 0
* Morrow:   σar = σa / (1 - σm/σ'f)
* SWT:      σar = sqrt(σmax σa), σmax = σm + σa; no damage (σar = 0) if σmax <= 0
* FKM:      the FKM guideline's Haigh diagram with mean-stress sensitivity M (M_σ of
            :mod:`fkm`; from Su by FKM's steel constants when not given), on the cycle's
            ray r = σm/σa: r < -1 (R > 1): σar = σa (1 - M); -1 <= r <= 1 (R <= 0):
            σar = σa + M σm; 1 < r < 3 (0 < R < 0.5): σar = (σa + M σm/3)(1 + M)/(1 + M/3);
            r >= 3 (R >= 0.5): σar = σa (1 + M)² 3/(3 + M). (FKM 6th ed. Sec 4.4.2.)
* none:     σar = σa

A mean at or beyond the strength (σm >= σu, or σ'f for Morrow) gives σar = inf (failure).
"""

from __future__ import annotations

import numpy as np

MEAN_STRESS_METHODS = ("none", "goodman", "gerber", "morrow", "swt", "fkm")


def fkm_amplitude(sa: np.ndarray, sm: np.ndarray, M: float) -> np.ndarray:
    """σar of the FKM Haigh diagram (module docstring), M the mean-stress sensitivity.
    A mean beyond the strength is not capped here (the static check is FKM's own)."""
    sa = np.asarray(sa, dtype=float)
    sm = np.asarray(sm, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(sa > 0.0, sm / np.where(sa > 0.0, sa, 1.0), 0.0)
    out = np.where(r < -1.0, sa * (1.0 - M), sa + M * sm)
    out = np.where((r > 1.0) & (r < 3.0), (sa + M * sm / 3.0) * (1.0 + M) / (1.0 + M / 3.0),
                   out)
    out = np.where(r >= 3.0, sa * (1.0 + M) ** 2 * 3.0 / (3.0 + M), out)
    return np.where(sa > 0.0, out, 0.0)


def equivalent_amplitude(
    sa: np.ndarray, sm: np.ndarray, method: str, Su: float, sf: float,
    M: float | None = None,
) -> np.ndarray:
    """Equivalent fully reversed amplitude σar (Pa) for amplitudes ``sa`` and means ``sm``;
    ``M`` the FKM mean-stress sensitivity (``"fkm"`` only; default from Su)."""
    sa = np.asarray(sa, dtype=float)
    sm = np.asarray(sm, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        if method == "none":
            return sa.copy()
        if method == "fkm":
            if M is None:
                from .fkm import mean_stress_sensitivity

                M = mean_stress_sensitivity(Su)
            return fkm_amplitude(sa, sm, M)
        if method == "goodman":
            den = 1.0 - sm / Su
        elif method == "gerber":
            den = np.where(sm > 0.0, 1.0 - (sm / Su) ** 2, 1.0)
        elif method == "morrow":
            den = 1.0 - sm / sf
        elif method == "swt":
            smax = sm + sa
            return np.sqrt(np.maximum(smax * sa, 0.0))
        else:
            raise ValueError(f"mean_stress must be one of {MEAN_STRESS_METHODS}, got {method!r}")
        return np.where(den > 0.0, sa / den, np.inf)
