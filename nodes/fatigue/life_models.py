"""Stress-life (Basquin) and strain-life (Coffin-Manson-Basquin with Neuber) lives.

Lives are returned as reversals to failure 2Nf (Nf = cycles). Stresses in Pa, strains in m/m.

* Basquin:  σar = σ'f (2Nf)^b, optionally no damage below the endurance limit Se.
* Coffin-Manson-Basquin:  εa = (σ'f - σm)/E (2Nf)^b + ε'f (2Nf)^c   (σm = 0 unless Morrow).
* Smith-Watson-Topper:  σmax εa = σ'f²/E (2Nf)^(2b) + σ'f ε'f (2Nf)^(b+c).
* Neuber's rule on the cyclic curve εa = σa/E + (σa/K')^(1/n'):  σ ε = σe²/E, with σe the
  linear-elastic FE stress (amplitude, or peak on first loading), σ, ε the local elastic-plastic
  values. Masing's hypothesis makes the range form identical to the amplitude form.
"""

from __future__ import annotations

import numpy as np

from .material import Material

MAX_REVERSALS = 1e30  # beyond this a cycle is treated as doing no damage (2Nf = inf)


def basquin_reversals(sar: np.ndarray, sf: float, b: float, Se: float | None = None) -> np.ndarray:
    """2Nf from Basquin, σar = σ'f (2Nf)^b. σar <= 0 (or < Se when given) -> inf."""
    sar = np.asarray(sar, dtype=float)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        rev = (sar / sf) ** (1.0 / b)
    rev = np.where(sar > 0.0, rev, np.inf)
    if Se is not None:
        rev = np.where(sar < Se, np.inf, rev)
    return rev


def solve_two_power(
    A1: np.ndarray, p1: float, A2: np.ndarray | float, p2: float, target: np.ndarray
) -> np.ndarray:
    """Solve A1 x^p1 + A2 x^p2 = target for x = 2Nf >= 1 (p1, p2 < 0; A1, A2 >= 0).

    Newton's method on y = ln x of ln(A1 e^(p1 y) + A2 e^(p2 y)) - ln(target), a convex
    decreasing function, started at y = 0 where it is >= 0: the iterates increase
    monotonically to the root. target <= 0 -> inf; left side < target at x = 1 -> 1.
    """
    A1 = np.asarray(A1, dtype=float)
    A2 = np.broadcast_to(np.asarray(A2, dtype=float), A1.shape)
    target = np.asarray(target, dtype=float)
    out = np.full(np.broadcast(A1, target).shape, np.inf)
    ok = (target > 0.0) & np.isfinite(target)
    a1, a2, tg = np.broadcast_arrays(A1, A2, target)
    a1, a2, tg = a1[ok], a2[ok], tg[ok]
    lt = np.log(tg)
    y = np.zeros_like(tg)
    # a good start: the larger of the two single-term roots (both are left of the root)
    with np.errstate(divide="ignore", invalid="ignore"):
        y1 = np.where(a1 > 0, (lt - np.log(a1)) / p1, 0.0)
        y2 = np.where(a2 > 0, (lt - np.log(a2)) / p2, 0.0)
    y = np.maximum(np.maximum(y1, y2), 0.0)
    y = np.minimum(y, np.log(MAX_REVERSALS))
    for _ in range(60):
        e1 = a1 * np.exp(p1 * y)
        e2 = a2 * np.exp(p2 * y)
        s = e1 + e2
        f = np.log(s) - lt
        df = (p1 * e1 + p2 * e2) / s
        step = -f / df
        y = y + step
        if np.all(np.abs(step) < 1e-12):
            break
    rev = np.exp(y)
    rev = np.where(y <= 0.0, 1.0, rev)
    rev = np.where(y >= np.log(MAX_REVERSALS), np.inf, rev)
    out[ok] = rev
    return out


def cyclic_strain(sa: np.ndarray, mat: Material) -> np.ndarray:
    """Strain amplitude on the cyclic curve, εa = σa/E + (σa/K')^(1/n')."""
    sa = np.abs(np.asarray(sa, dtype=float))
    return sa / mat.E + (sa / mat.K) ** (1.0 / mat.n)


def neuber(se: np.ndarray, mat: Material) -> np.ndarray:
    """Local stress σ (Pa) from elastic stress σe by Neuber: σ εcyc(σ) = σe²/E (σ, σe >= 0).

    Newton on x = ln σ of ln(σ²/E + σ (σ/K')^(1/n')) - ln(σe²/E), convex and increasing, started
    from the elastic value σ = σe (an upper bound): monotone convergence.
    """
    se = np.abs(np.asarray(se, dtype=float))
    out = np.zeros_like(se)
    pos = se > 0.0
    s = se[pos]
    if s.size == 0:
        return out
    m = 1.0 / mat.n
    lt = np.log(s * s / mat.E)
    x = np.log(s)
    lK = np.log(mat.K)
    for _ in range(200):
        # terms in log form to avoid overflow for large (σ/K')^(1/n')
        t1 = 2.0 * x - np.log(mat.E)
        t2 = x + m * (x - lK)
        big = np.maximum(t1, t2)
        lse = big + np.log(np.exp(t1 - big) + np.exp(t2 - big))
        w1 = np.exp(t1 - lse)
        df = 2.0 * w1 + (1.0 + m) * (1.0 - w1)
        step = -(lse - lt) / df
        x = x + step
        if np.all(np.abs(step) < 1e-13):
            break
    out[pos] = np.exp(x)
    return out


def cmb_reversals(ea: np.ndarray, mat: Material, sm: np.ndarray | float = 0.0) -> np.ndarray:
    """2Nf from Coffin-Manson-Basquin with Morrow's mean term (σm = 0 for none)."""
    ea = np.asarray(ea, dtype=float)
    A1 = (mat.sf - np.asarray(sm, dtype=float)) / mat.E
    A1 = np.broadcast_to(A1, ea.shape)
    rev = solve_two_power(np.maximum(A1, 0.0), mat.b, mat.ef, mat.c, ea)
    return np.where(A1 > 0.0, rev, np.where(ea > 0, 1.0, np.inf))


def swt_reversals(smax: np.ndarray, ea: np.ndarray, mat: Material) -> np.ndarray:
    """2Nf from Smith-Watson-Topper: σmax εa = σ'f²/E (2Nf)^2b + σ'f ε'f (2Nf)^(b+c)."""
    smax = np.asarray(smax, dtype=float)
    ea = np.asarray(ea, dtype=float)
    A1 = np.full(ea.shape, mat.sf**2 / mat.E)
    return solve_two_power(A1, 2 * mat.b, mat.sf * mat.ef, mat.b + mat.c, smax * ea)
