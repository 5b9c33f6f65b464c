"""The equivalent stress computed exactly only where rainflow needs it (#28): the numpy path.

Rainflow counting needs a history's turning points only (:func:`.counting.turning_points`),
and the extremes of a block are turning points or its first or last sample. On the Ch 6 arm
2.5 % of the node-samples are turning points, and the two float64 cosines of the principal
stress (:func:`.equivalent_stress.principal_extremes_of`) were half of the fatigue node's CPU.

:func:`turning_equivalent` therefore works in two passes over a block's stress components:

1. **Bracket every sample.** The stress invariants q, p, det are computed in float64 by the
   same code as the exact path (the same bits); r = det / (2 p p p) differs from the exact
   det / (2 p**3) by a few ulp (|Δr| <= 4e-16); arccos in float64; only the two cosines are
   taken in float32 (their argument rounded to float32: <= 1.9e-7; numpy's float32 cos:
   a few float32 ulp, <= 5e-7; the arccos of the perturbed r: <= sqrt(2 |Δr|) = 3e-8). So
   |cos error| <= 7.2e-7 and each principal stress σ = q + 2p cos(.) is within
   ``t = 2p * 4e-6 + 4e-15 (|q| + 2p)`` of the exact one (a margin of ~5 on the cosine term,
   ~9 on the float64 rounding of q + 2p cos). Where |σ1| and |σ3| are within 2.5 t the sign
   choice of the abs-max principal is uncertain and the bracket spans both.
2. **Exactly where it may matter.** A sample is left out only when the brackets prove the
   exact history strictly monotone through it (both differences to its neighbours of one
   sign). The first and last samples of the block are always kept. The exact equivalent
   stress (:func:`.equivalent_stress.equivalent_of`, elementwise, so the same bits as over
   the whole block) is computed at the kept samples, packed per node as
   :func:`.counting.turning_points` packs them (a superset of its turning points, which
   leaves the rainflow count, and the order in which a node's cycles close, unchanged).

``signed_von_mises`` has no transcendental beyond a square root: it is computed whole.

The compiled path (:mod:`.turning_eq`: numba, fused with the products) gives the same rows,
bit for bit; this one is its reference and the fallback without numba.
"""

from __future__ import annotations

import numpy as np

from .counting import turning_points
from .equivalent_stress import TILE_NODES, equivalent_of, invariants_of

COS_TOL = 4e-6
"""Bracket half-width per unit of 2p (the cosine term; see the module docstring)."""
ROUND_TOL = 4e-15
"""Bracket half-width per unit of |q| + 2p (float64 rounding)."""


def _brackets(ct: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) (k, n) bounds of the exact abs-max principal stress (Pa) of components
    ``ct`` (6, k, n) (each contiguous along samples)."""
    q, p, det = invariants_of(ct)
    with np.errstate(divide="ignore", invalid="ignore"):
        den = p * p
        den *= p
        den *= 2.0
        r = np.divide(det, den, out=den)
    r[~(p > 0.0)] = 0.0
    np.clip(r, -1.0, 1.0, out=r)
    phi = np.arccos(r, out=r)
    phi /= 3.0
    two_p = np.multiply(p, 2.0, out=p)
    th1 = phi.astype(np.float32)
    phi += 2.0 * np.pi / 3.0
    th3 = phi.astype(np.float32)
    s1 = np.cos(th1).astype(float)
    s1 *= two_p
    s1 += q
    s3 = np.cos(th3).astype(float)
    s3 *= two_p
    s3 += q
    tol = np.abs(q)
    tol += two_p
    tol *= ROUND_TOL
    tol += COS_TOL * two_p
    a1, a3 = np.abs(s1), np.abs(s3)
    gap = a1 - a3
    sure1 = gap > 2.5 * tol
    sure3 = gap < -2.5 * tol
    lo = np.where(sure1, s1, np.where(sure3, s3, np.minimum(s1, s3)))
    hi = np.where(sure1, s1, np.where(sure3, s3, np.maximum(s1, s3)))
    lo -= tol
    hi += tol
    return lo, hi


def kept_samples(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(k, n) True where a sample may be a turning point (or is a block end), from brackets
    ``lo <= x <= hi`` of the exact history (k nodes, n samples)."""
    k, n = lo.shape
    keep = np.ones((k, n), dtype=bool)
    if n <= 2:
        return keep
    up = lo[:, 1:] > hi[:, :-1]  # x[j] > x[j-1] surely
    down = hi[:, 1:] < lo[:, :-1]  # x[j] < x[j-1] surely
    through = (up[:, :-1] & up[:, 1:]) | (down[:, :-1] & down[:, 1:])
    keep[:, 1:-1] = ~through
    return keep


def turning_equivalent(comp: np.ndarray, kind: str, previous: np.ndarray | None
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The rows rainflow needs of one block's equivalent stress, and the block's extremes.

    Args:
        comp: (6, n, k) stress components (Pa) of k nodes over n samples, as
            :func:`.superposition.superpose_components` gives them.
        kind: the equivalent stress (:data:`.equivalent_stress.EQUIVALENTS`).
        previous: (k,) the last equivalent stress fed before this block, or None.

    Returns:
        ``rows`` (m, k): each node's candidate turning points in order, padded by repeating
        its last sample (feed to :meth:`.counting.StreamingRainflow.feed_points`);
        ``last`` (k,): the block's last equivalent stress; ``hi``, ``lo`` (k,): its largest
        and smallest equivalent stress. All exact (the bits of the whole-block path).
    """
    n = comp.shape[1]
    if kind != "abs_max_principal" or n <= 2:
        eq = equivalent_of(comp, kind)
        return turning_points(eq, previous), eq[-1].copy(), eq.max(axis=0), eq.min(axis=0)
    ct = comp.transpose(0, 2, 1)  # (6, k, n)
    # a NaN bracket proves nothing: such samples are kept and computed exactly
    lo = np.empty(ct.shape[1:])
    hi = np.empty(ct.shape[1:])
    for j in range(0, ct.shape[1], TILE_NODES):  # in cache (see TILE_NODES)
        lo[j:j + TILE_NODES], hi[j:j + TILE_NODES] = _brackets(ct[:, j:j + TILE_NODES])
    keep = kept_samples(lo, hi)
    node, sample = np.nonzero(keep)  # node-major, samples in order
    vals = equivalent_of(np.ascontiguousarray(ct[:, node, sample]), kind)
    counts = keep.sum(axis=1)
    starts = np.zeros(counts.size, dtype=np.int64)
    np.cumsum(counts[:-1], out=starts[1:])
    last = vals[starts + counts - 1]
    hi_e = np.maximum.reduceat(vals, starts)
    lo_e = np.minimum.reduceat(vals, starts)
    m = int(counts.max())
    rows = np.empty((m, counts.size))
    rows[:] = last[None, :]
    rows[np.arange(vals.size) - np.repeat(starts, counts), node] = vals
    return rows, last, hi_e, lo_e
