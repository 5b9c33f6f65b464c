"""Test oracles of the fatigue engine's one (compiled) path: the same idea in numpy (#28, #42).

The product computes a block by :func:`nodes.fatigue.lib.turning_eq.superpose_gather` and
:func:`nodes.fatigue.lib.turning_eq.kept_equivalent` (numba; the bracket's proof is in that
module's docstring) and counts with :meth:`nodes.fatigue.lib.counting.StreamingRainflow.
feed_packed`. Here, for the bit-equality tests only:

* :func:`turning_equivalent`: the bracket in numpy (float32 cosines; the proof below), the
  kept-sample test and the exact values at the kept samples, packed per node as
  :func:`turning_points` packs them;
* :func:`exact_numpy` / :func:`exact_block`: drop-in replacements of the worker's
  ``_Engine._exact_compiled`` (monkeypatched by the tests): in chunks of samples over all
  nodes, the numpy turning points, or the equivalent stress of every sample (the reference),
  counted by the lock-step counter;
* :func:`repeated_lock_step`: the repeated residue by the lock-step counter;
* :func:`turning_points`, :func:`lock_step`, :func:`feed_lock_step`: the lock-step counter
  (every history advanced together in numpy over a block's possible turning points), the
  plain form of the product's compiled counter.

The numpy bracket. The stress invariants q, p, det are computed in float64 by the
same code as the exact path (the same bits); r = det / (2 p p p) differs from the exact
det / (2 p**3) by a few ulp (|Δr| <= 4e-16); arccos in float64; only the two cosines are
taken in float32 (their argument rounded to float32: <= 1.9e-7; numpy's float32 cos:
a few float32 ulp, <= 5e-7; the arccos of the perturbed r: <= sqrt(2 |Δr|) = 3e-8). So
|cos error| <= 7.2e-7 and each principal stress σ = q + 2p cos(.) is within
``t = 2p * 4e-6 + 4e-15 (|q| + 2p)`` of the exact one (a margin of ~5 on the cosine term,
~9 on the float64 rounding of q + 2p cos). Where |σ1| and |σ3| are within 2.5 t the sign
choice of the abs-max principal is uncertain and the bracket spans both. A sample is left
out only when the brackets prove the exact history strictly monotone through it; the first
and last samples of the block are always kept.
"""

from __future__ import annotations

import numpy as np

from nodes.fatigue.lib.counting import Cycles, StreamingRainflow
from nodes.fatigue.lib.equivalent_stress import TILE_NODES, equivalent_of, invariants_of
from nodes.fatigue.lib.superposition import ROWS, superpose_components
from nodes.fatigue.lib.turning_eq import ROUND_TOL


def turning_points(block: np.ndarray, previous: np.ndarray | None) -> np.ndarray:
    """Keep only the samples of a block that can be turning points, packed per column.

    Args:
        block: (n_samples, n_series) consecutive samples of every history.
        previous: (n_series,) last sample fed before this block, or None at the start.

    Returns:
        (m, n_series) array, m <= n_samples: each column holds that history's candidate
        turning points in order (plus the block's last sample), padded at the end by
        repeating the block's last sample. Feeding the padded rows is a no-op for the
        counter (equal samples are skipped), so the count is unchanged.
    """
    x = np.asarray(block, dtype=float)
    n, _ = x.shape
    if n <= 2:
        return x
    if previous is None:
        prev = x[:1]
    else:
        prev = np.asarray(previous, dtype=float)[None, :]
    ext = np.vstack([prev, x])
    d = np.diff(ext, axis=0)  # d[j] = x[j] - x[j-1]
    keep = np.empty(x.shape, dtype=bool)
    keep[:-1] = d[:-1] * d[1:] <= 0.0
    keep[-1] = True
    if previous is None:
        keep[0] = True
    counts = keep.sum(axis=0)
    m = int(counts.max())
    if m >= n:
        return x
    order = np.argsort(~keep, axis=0, kind="stable")[:m]
    packed = np.take_along_axis(x, order, axis=0)
    rows = np.arange(m)[:, None]
    return np.where(rows < counts[None, :], packed, x[-1][None, :])


def lock_step(self: StreamingRainflow, rows_in: np.ndarray) -> Cycles:
    """The lock-step counter: every history of ``self`` advanced by the rows (n, n_series)
    together, in numpy (the product's kernel runs history by history)."""
    out_i: list[np.ndarray] = []
    out_b: list[np.ndarray] = []
    out_c: list[np.ndarray] = []
    rows = np.arange(self.n)
    for x in rows_in:
        if int(self._depth.max()) + 1 >= self._cap:
            self._grow()
        S, d = self._stack, self._depth
        empty = d == 0
        top = S[rows, np.maximum(d - 1, 0)]
        prev = S[rows, np.maximum(d - 2, 0)]
        dx = x - top
        extend = (d >= 2) & (dx * (top - prev) > 0.0)
        push = empty | ((dx != 0.0) & ~extend)
        idx = np.maximum(d - 1, 0) + (push & ~empty)
        S[rows, idx] = np.where(push | extend, x, top)
        d += push
        cand = rows[d >= 4]
        while cand.size:
            dc = d[cand]
            a = S[cand, dc - 4]
            b = S[cand, dc - 3]
            c = S[cand, dc - 2]
            e = S[cand, dc - 1]
            r = np.abs(b - c)
            hit = (r <= np.abs(a - b)) & (r <= np.abs(c - e))
            if not hit.any():
                break
            h = cand[hit]
            out_i.append(h)
            out_b.append(b[hit])
            out_c.append(c[hit])
            S[h, dc[hit] - 3] = e[hit]
            d[h] -= 2
            cand = h[d[h] >= 4]
    if not out_i:
        return Cycles.empty()
    s = np.concatenate(out_i)
    return Cycles(s, np.concatenate(out_b), np.concatenate(out_c), np.ones(s.size))


def feed_lock_step(rf: StreamingRainflow, block: np.ndarray) -> Cycles:
    """``rf.feed(block)`` by the lock-step counter over the block's turning points."""
    x = np.asarray(block, dtype=float)
    if x.shape[0] == 0:
        return Cycles.empty()
    rows_in = turning_points(x, rf._last)
    rf._last = x[-1].copy()
    return lock_step(rf, rows_in)


COS_TOL = 4e-6
"""Bracket half-width per unit of 2p (the cosine term; see the module docstring)."""


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
            :func:`nodes.fatigue.lib.superposition.superpose_components` gives them.
        kind: the equivalent stress (:data:`nodes.fatigue.lib.equivalent_stress.EQUIVALENTS`).
        previous: (k,) the last equivalent stress fed before this block, or None.

    Returns:
        ``rows`` (m, k): each node's candidate turning points in order, padded by repeating
        its last sample (feed to :func:`feed_points`);
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


def feed_points(rf: StreamingRainflow, rows: np.ndarray, last: np.ndarray) -> Cycles:
    """Advance every history of ``rf`` by a block given as :func:`turning_equivalent`'s
    ``rows`` (m, n) and ``last`` (n,) by the lock-step counter: the cycles of feeding the
    whole block."""
    x = np.asarray(rows, dtype=float)
    assert x.ndim == 2 and x.shape[1] == rf.n and np.shape(last) == (rf.n,)
    if x.shape[0] == 0:
        return Cycles.empty()
    rf._last = np.array(last, dtype=float)
    return lock_step(rf, x)


def _exact_chunks(engine, F: np.ndarray, idx: np.ndarray, rf: StreamingRainflow,
                  block: bool) -> tuple[np.ndarray, np.ndarray, Cycles]:
    coef = engine.per_node[idx]
    rows = max(ROWS, (2_000_000 // (6 * idx.size)) // ROWS * ROWS)
    hi = np.full(idx.size, -np.inf)
    lo = np.full(idx.size, np.inf)
    parts = []
    for i in range(0, F.shape[0], rows):
        comp = superpose_components(F[i:i + rows], coef)
        if block:
            eq = equivalent_of(comp, engine.cfg.equivalent)
            bhi, blo = eq.max(axis=0), eq.min(axis=0)
            parts.append(feed_lock_step(rf, eq))
        else:
            pts, last, bhi, blo = turning_equivalent(comp, engine.cfg.equivalent, rf.last)
            parts.append(feed_points(rf, pts, last))
        np.maximum(hi, bhi, out=hi)
        np.minimum(lo, blo, out=lo)
    return hi, lo, Cycles.concat(parts)


def exact_numpy(engine, F: np.ndarray, idx: np.ndarray, rf: StreamingRainflow
                ) -> tuple[np.ndarray, np.ndarray, Cycles]:
    """``_Engine._exact_compiled`` in numpy: the equivalent stress only where it may be a
    turning point (:func:`turning_equivalent`), the lock-step counter."""
    return _exact_chunks(engine, F, idx, rf, False)


def exact_block(engine, F: np.ndarray, idx: np.ndarray, rf: StreamingRainflow
                ) -> tuple[np.ndarray, np.ndarray, Cycles]:
    """``_Engine._exact_compiled`` the plain way: the equivalent stress of every sample
    (the reference), the lock-step counter."""
    return _exact_chunks(engine, F, idx, rf, True)


def repeated_lock_step(rf: StreamingRainflow) -> Cycles:
    """``rf.residue_cycles("repeated")`` by the lock-step counter on a copy: each history's
    residue fed again, padded with its last point (a no-op for the counter)."""
    d = rf._depth
    if int(d.max()) == 0:
        return Cycles.empty()
    other = rf.copy()
    cols = np.arange(int(d.max()))
    take = np.minimum(cols[None, :], np.maximum(d - 1, 0)[:, None])
    return lock_step(other, rf._stack[np.arange(rf.n)[:, None], take].T)
