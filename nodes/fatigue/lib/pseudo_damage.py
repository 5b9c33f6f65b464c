"""Pseudo-damage and range-mean rainflow matrices of load (or stress) histories.

**Pseudo-damage** compares load histories without a component model (a simulation against
a rig or road measurement, one run against another): each channel's rainflow cycles
(ranges ΔF_i [N or N m], counts n_i: 1 full, 0.5 half) are summed on a reference S-N line of
slope k through (N_ref, ΔF_ref):

    D_pseudo = Σ n_i (ΔF_i / ΔF_ref)^k / N_ref,

and the damage-equivalent range at N_ref cycles is ΔF_eq = ΔF_ref (D_pseudo)^(1/k)
(the constant range that, applied N_ref times, does the same pseudo-damage). The reference
slope is **k = 5** by default: FKM's slope for non-welded steel components (the arm's own
method); the absolute value of D depends on ΔF_ref and N_ref, the ratio of two histories on
k only. Defaults ΔF_ref = 1 kN (1 kN m for a moment), N_ref = 1e6.

**Rainflow matrix**: the cycles' counts binned by range and mean (``n_bins`` x ``n_bins``
equal bins from 0 to the largest range and from the lowest to the highest mean).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .counting import Cycles, count_series

K_REF = 5.0
"""Reference slope of the pseudo-damage S-N line (FKM non-welded steel)."""
N_REF = 1.0e6
"""Reference cycles of the pseudo-damage line."""


def reference_range(channel: str) -> float:
    """ΔF_ref: 1 kN for a force channel, 1 kN m for a moment (``..._mx``)."""
    return 1.0e3


def pseudo_damage(cycles: Cycles, k: float = K_REF, ref_range: float = 1.0e3,
                  n_ref: float = N_REF) -> float:
    """D_pseudo = Σ n_i (ΔF_i / ΔF_ref)^k / N_ref of one history's cycles (module docstring)."""
    if not (k > 0 and ref_range > 0 and n_ref > 0):
        raise ValueError(f"k, ref_range, n_ref must be > 0, got {k}, {ref_range}, {n_ref}")
    if len(cycles) == 0:
        return 0.0
    return float(np.sum(cycles.count * (cycles.range / ref_range) ** k) / n_ref)


def equivalent_range(d: float, k: float = K_REF, ref_range: float = 1.0e3) -> float:
    """ΔF_eq at N_ref cycles of a pseudo-damage d: ΔF_ref d^(1/k)."""
    return float(ref_range * d ** (1.0 / k))


@dataclass(frozen=True)
class ChannelPseudoDamage:
    """One channel's pseudo-damage (module docstring)."""

    channel: str
    cycles: float
    max_range: float
    pseudo_damage: float
    equivalent_range: float
    k: float
    ref_range: float
    n_ref: float

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def channel_pseudo_damage(loads: Mapping[str, np.ndarray], k: float = K_REF,
                          residue: str = "half_cycles", n_ref: float = N_REF
                          ) -> list[ChannelPseudoDamage]:
    """Pseudo-damage of every channel of ``loads`` (name -> history)."""
    out = []
    for name, v in loads.items():
        cyc = count_series(np.asarray(v, dtype=float), residue)
        ref = reference_range(name)
        d = pseudo_damage(cyc, k, ref, n_ref)
        out.append(ChannelPseudoDamage(
            channel=name, cycles=float(cyc.count.sum()) if len(cyc) else 0.0,
            max_range=float(cyc.range.max()) if len(cyc) else 0.0, pseudo_damage=d,
            equivalent_range=equivalent_range(d, k, ref), k=k, ref_range=ref, n_ref=n_ref))
    return out


def rainflow_matrix(cycles: Cycles, n_bins: int = 32) -> dict:
    """Range-mean matrix: ``{"range_edges", "mean_edges", "counts"[range_bin][mean_bin]}``."""
    if len(cycles) == 0:
        return {"range_edges": [0.0, 1.0], "mean_edges": [0.0, 1.0], "counts": [[0.0]]}
    r, m = cycles.range, cycles.mean
    r_hi = float(r.max()) or 1.0
    m_lo, m_hi = float(m.min()), float(m.max())
    if m_hi <= m_lo:
        m_lo, m_hi = m_lo - 0.5, m_hi + 0.5
    H, re, me = np.histogram2d(r, m, bins=n_bins, range=[[0.0, r_hi], [m_lo, m_hi]],
                               weights=cycles.count)
    return {"range_edges": re.tolist(), "mean_edges": me.tolist(), "counts": H.tolist()}


def matrix_rows(series: str, unit: str, mat: dict) -> list[list]:
    """Long-form rows (series, unit, range_lo, range_hi, mean_lo, mean_hi, cycles) of the
    non-empty bins of a `rainflow_matrix`."""
    re, me, H = mat["range_edges"], mat["mean_edges"], np.asarray(mat["counts"])
    return [[series, unit, re[i], re[i + 1], me[j], me[j + 1], float(H[i, j])]
            for i, j in zip(*np.nonzero(H), strict=True)]
