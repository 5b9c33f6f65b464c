"""Mean-stress corrections: equivalent fully reversed stress amplitude σar (Pa).

Each takes the cycle's stress amplitude σa and mean σm (Pa) and returns the amplitude that
would do the same damage at zero mean:

* Goodman:  σar = σa / (1 - σm/σu)          (applied to compressive means too: beneficial)
* Gerber:   σar = σa / (1 - (σm/σu)^2)      for σm > 0; no correction for σm <= 0
* Morrow:   σar = σa / (1 - σm/σ'f)
* SWT:      σar = sqrt(σmax σa), σmax = σm + σa; no damage (σar = 0) if σmax <= 0
* none:     σar = σa

A mean at or beyond the strength (σm >= σu, or σ'f for Morrow) gives σar = inf (failure).
"""

from __future__ import annotations

import numpy as np

MEAN_STRESS_METHODS = ("none", "goodman", "gerber", "morrow", "swt")


def equivalent_amplitude(
    sa: np.ndarray, sm: np.ndarray, method: str, Su: float, sf: float
) -> np.ndarray:
    """Equivalent fully reversed amplitude σar (Pa) for amplitudes ``sa`` and means ``sm``."""
    sa = np.asarray(sa, dtype=float)
    sm = np.asarray(sm, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        if method == "none":
            return sa.copy()
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
