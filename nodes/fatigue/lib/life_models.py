"""Stress-life (Basquin) and strain-life (Coffin-Manson-Basquin with Neuber) lives.

Lives are returned as reversals to failure 2Nf (Nf = cycles). Stresses in Pa, strains in m/m.

* Basquin:  σar = σ'f (2Nf)^b, optionally no damage below the endurance limit Se.
* `SNCurve`: a Basquin line with a knee (2N_D, Se), an endurance treatment below the knee
  ("elementary" Miner: no damage; "haibach": slope k' = 2k - 1, k = -1/b; "none": the line
  continued) and optionally a low-cycle segment (Shigley's line from (1 cycle, Su)).
* Coffin-Manson-Basquin:  εa = (σ'f - σm)/E (2Nf)^b + ε'f (2Nf)^c   (σm = 0 unless Morrow).
* Smith-Watson-Topper:  σmax εa = σ'f²/E (2Nf)^(2b) + σ'f ε'f (2Nf)^(b+c).
* Neuber's rule on the cyclic curve εa = σa/E + (σa/K')^(1/n'):  σ ε = σe²/E, with σe the
  linear-elastic FE stress (amplitude, or peak on first loading), σ, ε the local elastic-plastic
  values. Masing's hypothesis makes the range form identical to the amplitude form.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .material import Material

ENDURANCE_MODES = ("haibach", "elementary", "none")
"""Treatment of cycles whose equivalent amplitude σar is below the endurance limit Se."""

MAX_REVERSALS = 1e30  # beyond this a cycle is treated as doing no damage (2Nf = inf)


def below_knee(rev: np.ndarray, sar: np.ndarray, Se: float, knee_reversals: float, k: float,
               endurance: str) -> np.ndarray:
    """Apply the endurance treatment to reversals ``rev`` of cycles of equivalent amplitude σar.

    For σar < Se: "elementary" (Palmgren-Miner elementary rule) -> inf (no damage);
    "haibach" (Haibach's modified Miner rule) -> 2N = 2N_D (Se/σar)^(2k-1), the line through
    the knee (2N_D, Se) with slope k' = 2k - 1, k = -1/b the slope above the knee;
    "none" -> ``rev`` unchanged. σar >= Se is never changed. Stresses in Pa.
    """
    if endurance not in ENDURANCE_MODES:
        raise ValueError(f"endurance must be one of {ENDURANCE_MODES}, got {endurance!r}")
    rev = np.asarray(rev, dtype=float)
    sar = np.asarray(sar, dtype=float)
    if endurance == "none":
        return rev
    low = sar < Se
    if endurance == "elementary":
        return np.where(low, np.inf, rev)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        hb = knee_reversals * (Se / sar) ** (2.0 * k - 1.0)
    return np.where(low, np.where(sar > 0.0, hb, np.inf), rev)


@dataclass(frozen=True)
class SNCurve:
    """A stress-life curve in Basquin form with a knee, validated when built.

    σar = σ'f (2N)^b for σar between the knee (2N_D, Se) and, if ``lcf_Su`` is given, the
    low-cycle point (``lcf_reversals``, σ'f lcf_reversals^b); above that point the log-log line
    to (2 reversals, Su) (Shigley's low-cycle segment from (1 cycle, Sut) to (10³, f Sut));
    below Se the ``endurance`` treatment of `below_knee`. Stresses in Pa, lives in reversals
    2N. ``meta`` carries the factors the curve was derived from (for the summary).
    """

    sf: float
    b: float
    Se: float
    knee_reversals: float
    endurance: str = "haibach"
    lcf_Su: float | None = None
    lcf_reversals: float = 2.0e3
    name: str = ""
    meta: Mapping = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        if not (np.isfinite(self.sf) and self.sf > 0.0):
            raise ValueError(f"sf must be > 0, got {self.sf!r}")
        if not (np.isfinite(self.b) and self.b < 0.0):
            raise ValueError(f"b must be negative, got {self.b!r}")
        if not (np.isfinite(self.Se) and 0.0 < self.Se < self.sf):
            raise ValueError(f"Se must be in (0, sf), got {self.Se!r}")
        if not (np.isfinite(self.knee_reversals) and self.knee_reversals > 1.0):
            raise ValueError(f"knee_reversals must be > 1, got {self.knee_reversals!r}")
        if self.endurance not in ENDURANCE_MODES:
            raise ValueError(f"endurance must be one of {ENDURANCE_MODES}, "
                             f"got {self.endurance!r}")
        if self.lcf_Su is not None and not (2.0 < self.lcf_reversals < self.knee_reversals
                                             and self.lcf_Su > self.lcf_stress):
            raise ValueError("the low-cycle point must lie between 2 reversals (at Su) and "
                             "the knee, below Su")

    @property
    def k(self) -> float:
        """S-N slope above the knee, k = -1/b (N ∝ σ^-k)."""
        return -1.0 / self.b

    @property
    def k_haibach(self) -> float:
        """Haibach's slope below the knee, k' = 2k - 1."""
        return 2.0 * self.k - 1.0

    @property
    def lcf_stress(self) -> float:
        """σar at the low-cycle point (f Sut for a Shigley curve)."""
        return self.sf * self.lcf_reversals**self.b

    def with_endurance(self, endurance: str) -> SNCurve:
        """The same curve with another endurance treatment."""
        return replace(self, endurance=endurance)

    def reversals(self, sar: np.ndarray) -> np.ndarray:
        """2N of equivalent fully reversed amplitudes σar (Pa); σar <= 0 -> inf."""
        sar = np.asarray(sar, dtype=float)
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
            rev = (sar / self.sf) ** (1.0 / self.b)
            if self.lcf_Su is not None:
                s3 = self.lcf_stress
                b_lcf = np.log(s3 / self.lcf_Su) / np.log(self.lcf_reversals / 2.0)
                rev = np.where(sar > s3, 2.0 * (sar / self.lcf_Su) ** (1.0 / b_lcf), rev)
        rev = below_knee(rev, sar, self.Se, self.knee_reversals, self.k, self.endurance)
        return np.where(sar > 0.0, rev, np.inf)

    def stress(self, reversals: np.ndarray) -> np.ndarray:
        """σar (Pa) at lives 2N (the inverse of `reversals` where it is finite)."""
        r = np.asarray(reversals, dtype=float)
        s = self.sf * r**self.b
        if self.lcf_Su is not None:
            b_lcf = np.log(self.lcf_stress / self.lcf_Su) / np.log(self.lcf_reversals / 2.0)
            s = np.where(r < self.lcf_reversals, self.lcf_Su * (r / 2.0) ** b_lcf, s)
        if self.endurance == "haibach":
            s = np.where(r > self.knee_reversals,
                         self.Se * (r / self.knee_reversals) ** (-1.0 / self.k_haibach), s)
        elif self.endurance == "elementary":
            s = np.where(r > self.knee_reversals, self.Se, s)
        return s

    def as_dict(self) -> dict:
        """JSON-able description (stresses in Pa)."""
        return {"name": self.name, "sf_pa": self.sf, "b": self.b, "k": self.k,
                "Se_pa": self.Se, "knee_reversals": self.knee_reversals,
                "knee_cycles": 0.5 * self.knee_reversals, "endurance": self.endurance,
                "k_below_knee": {"haibach": self.k_haibach, "elementary": None,
                                 "none": self.k}[self.endurance],
                "low_cycle_segment": None if self.lcf_Su is None else
                {"from": [1.0, self.lcf_Su], "to": [0.5 * self.lcf_reversals,
                                                    self.lcf_stress]},
                **dict(self.meta)}


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
    act = np.arange(y.size)  # each root iterated until its own step is small: its value
    for _ in range(60):      # does not depend on which other cycles share the call
        e1 = a1[act] * np.exp(p1 * y[act])
        e2 = a2[act] * np.exp(p2 * y[act])
        s = e1 + e2
        step = -(np.log(s) - lt[act]) / ((p1 * e1 + p2 * e2) / s)
        y[act] += step
        act = act[np.abs(step) >= 1e-12]
        if act.size == 0:
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
    act = np.arange(x.size)  # each value iterated until its own step is small (as above)
    for _ in range(200):
        # terms in log form to avoid overflow for large (σ/K')^(1/n')
        xa = x[act]
        t1 = 2.0 * xa - np.log(mat.E)
        t2 = xa + m * (xa - lK)
        big = np.maximum(t1, t2)
        lse = big + np.log(np.exp(t1 - big) + np.exp(t2 - big))
        w1 = np.exp(t1 - lse)
        df = 2.0 * w1 + (1.0 + m) * (1.0 - w1)
        step = -(lse - lt[act]) / df
        x[act] = xa + step
        act = act[np.abs(step) >= 1e-13]
        if act.size == 0:
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
