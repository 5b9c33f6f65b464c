"""The equivalent stress computed exactly only where rainflow needs it: compiled.

Rainflow counting needs a history's turning points only, and the extremes of a block are turning
points or its first or last sample. On the Ch 6 arm 2.5 % of the node-samples are turning points,
and the two float64 cosines of the principal stress
(:func:`.equivalent_stress.principal_extremes_of`) were half of the fatigue node's CPU. So each
node's abs-max principal stress is *bracketed* at every sample (lo <= exact <= hi, proven below;
where |σ1| and |σ3| may be equal the bracket spans both signs); a sample is left out only when the
brackets prove the exact history strictly monotone through it (both differences to its neighbours of
one sign); the block's first and last samples are always kept. The exact equivalent stress
(:func:`.equivalent_stress.equivalent_of`, elementwise, so the same bits as over the whole block) is
computed at the kept samples only: a superset of the turning points, which leaves the rainflow
count, and the order in which a node's cycles close, unchanged. ``signed_von_mises`` has no
transcendental beyond a square root: it is computed at every sample. This is the product's one
implementation (numba is a dependency); the same idea in numpy (float32 cosines, another bracket:
other samples kept) is the tests' oracle, ``tests/fatigue/oracle_turning_eq.py``: both give the same
cycles, bit for bit.

**No transcendentals:** :func:`kept_equivalent` does the bracket, the kept-sample test and
the gathering in one pass per node (:func:`_keep_gather`, no temporaries), with a bracket that
needs no transcendental at all (scalar ``acos``/``cos`` per node-sample would cost more than
the whole budget): the largest root c1 of 4c³ - 3c = r (σ1 = q + 2p c1) is a smooth function
of u = sqrt(1 + r) (the double root at r = -1 is a square-root branch point in r), fitted once
by a degree-9 polynomial P(u) (|P - c1| <= 1.4e-9 on [0, sqrt 2]); the smallest root is
c3(r) = -c1(-r) (u = sqrt(1 - r)). P only proposes: the bracket [P - E, P + E] (E = 1e-7) is
*proven* at run time by the sign of g(c) = 4c³ - 3c - r at its ends, beyond a margin DELTA
that covers the rounding of g and the difference between this r (det / (2 p p p)) and the
exact path's (det / (2 p**3)); g is increasing on c >= 1/2 and c1 >= 1/2, so an end that fails
its check falls back to the hard bound (1/2 below, 1 above) and the bracket stays valid.
q, p, det are computed by the operations of :func:`.equivalent_stress.invariants_of` in their
order (the same bits; numba without fastmath neither fuses nor reorders). The exact path's
acos/cos then differ from the root by far less than C64_TOL (a few ulp), its rounding of
q + 2p c by less than ROUND_TOL. The exact values at the kept samples go to
:meth:`.counting.StreamingRainflow.feed_packed`.

**Fused with the products:** :func:`superpose_gather` computes a node's stresses
(:func:`_node_products`, :mod:`.superposition`'s sum in case order) into a 6 x n scratch that
stays in cache and brackets and gathers them at once (:func:`_node_keep`, in stages over the
node's samples), node after node: no tile written out and read back, no per-tile Python call.
"""

from __future__ import annotations

import numpy as np

from .counting import compile_kernels
from .equivalent_stress import equivalent_of

ROUND_TOL = 4e-15
"""Bracket half-width per unit of |q| + 2p: the float64 rounding of q + 2p c (a margin of ~9)."""

ROOT_POLY = (0.5000000013442235, 0.40824818198579, -0.055553386430064314,
             0.018881567793504486, -0.008142182128495918, 0.003791443524522732,
             -0.0016693372451981716, 0.0005941030627756393, -0.00014092219951476883,
             1.593410329717697e-05)
"""P(u) ~ c1(r), u = sqrt(1 + r): least squares, |P - c1| <= 1.4e-9 (only proposes a root;
the bracket is proven by :data:`ROOT_E` and :data:`DELTA`)."""
ROOT_E = 1e-7
"""Half-width of the proposed root bracket in c (>> |P - c1|; at the double root r = -1,
g(c1 + e) >= 6 e**2 > DELTA needs e > 5.8e-8)."""
DELTA = 2e-14
"""Margin on g(c) = 4c³ - 3c - r: its float64 rounding (<= 4.5e-15 for |c| <= 1.0000002) plus
|r - r_exact| (this r = det / (2 p p p) against det / (2 p**3) with the exact path's pow:
<= 4 ulp, 9e-16)."""
C64_TOL = 5e-14
"""Largest distance (per unit of 2p) between the exact path's cos(acos(r) / 3 [+ 2π/3]) in
float64 and the true root (a few ulp of acos, cos and the constant 2π/3: <= 5e-15)."""


_P0, _P1, _P2, _P3, _P4, _P5, _P6, _P7, _P8, _P9 = ROOT_POLY
def _root1(r):  # type: ignore[no-untyped-def]
    """[lo, hi] containing the largest root of 4c³ - 3c = r' for every r' within DELTA
    (minus g's rounding) of r, r in [-1, 1]."""
    u = np.sqrt(1.0 + r)
    c = _P9 * u + _P8
    c = c * u + _P7
    c = c * u + _P6
    c = c * u + _P5
    c = c * u + _P4
    c = c * u + _P3
    c = c * u + _P2
    c = c * u + _P1
    c = c * u + _P0
    a = c - ROOT_E
    b = c + ROOT_E
    ga = (4.0 * a * a - 3.0) * a - r
    gb = (4.0 * b * b - 3.0) * b - r
    lo = a if (a >= 0.5) & (ga < -DELTA) else 0.5
    hi = b if (b >= 0.5) & (gb > DELTA) else 1.0
    return lo, hi


def _node_keep(buf, i, n, out, pos, lo, hi, w):  # type: ignore[no-untyped-def]  # noqa: C901
    """Node ``i`` of buf (6, k, >= n) [Pa]: the brackets of its abs-max principal stress
    (into lo, hi: scratch of n), its kept samples' components written to out (6, cap) from
    column pos (room for n assumed); w: scratch (6, >= n). Returns how many.

    In stages over the node's samples (invariants; r; the largest root; the smallest root
    and the bracket; the kept test; the gather), each a short loop of independent samples:
    one loop doing it all would be one long dependency chain per sample that the core cannot
    overlap across samples. The same operations on the same values: the same bits."""
    wq = w[0]
    wp = w[1]
    wt = w[2]
    wr = w[3]
    wa = w[4]
    wb = w[5]
    for j in range(n):  # the invariants (the operations of invariants_of, in its order)
        sx = buf[0, i, j]
        sy = buf[1, i, j]
        sz = buf[2, i, j]
        txy = buf[3, i, j]
        tyz = buf[4, i, j]
        tzx = buf[5, i, j]
        q = sx + sy
        q += sz
        q /= 3.0
        a = sx - q
        b = sy - q
        c = sz - q
        p1 = txy * txy
        p1 += tyz * tyz
        p1 += tzx * tzx
        p2 = a * a
        p2 += b * b
        p2 += c * c
        p1 *= 2.0
        p2 += p1
        p2 /= 6.0
        p = np.sqrt(p2)
        det = a * b
        det *= c
        u = txy * 2.0
        u *= tyz
        u *= tzx
        det += u
        det -= (a * tyz) * tyz
        det -= (b * tzx) * tzx
        det -= (c * txy) * txy
        two_p = p * 2.0
        aq = abs(q)
        t = ROUND_TOL * (aq + two_p) + C64_TOL * two_p
        ok = (aq < 1e300) & (det - det == 0.0) & (p < 1e90)  # else NaN, inf
        wq[j] = q
        wp[j] = two_p
        wt[j] = t if ok else np.nan  # NaN: the sample is kept, (-inf, inf)
        wr[j] = det
        wa[j] = p
    for j in range(n):  # r (NaN: tiny p, c in [-1, 1]; p == 0: exactly q)
        p = wa[j]
        big = p > 1e-90
        pp = p if big else 1.0
        r = wr[j] / (pp * pp * pp * 2.0)
        r = min(max(r, -1.0), 1.0)
        wr[j] = r if big else np.nan
    for j in range(n):  # the largest root's bracket
        r = wr[j]
        big = r == r
        l1, h1 = _root1(r if big else 0.0)
        wa[j] = l1 if big else -1.0
        wb[j] = h1 if big else 1.0
    for j in range(n):  # the smallest root's, and the abs-max principal's bracket
        r = wr[j]
        big = r == r
        l3, h3 = _root1(-r if big else 0.0)
        l3 = l3 if big else -1.0
        h3 = h3 if big else 1.0
        l1 = wa[j]
        h1 = wb[j]
        q = wq[j]
        two_p = wp[j]
        t = wt[j]
        s1l = q + two_p * l1 - t
        s1h = q + two_p * h1 + t
        s3l = q - two_p * h3 - t
        s3h = q - two_p * l3 + t
        m1 = max(abs(s1l), abs(s1h))
        n1 = 0.0 if (s1l <= 0.0) & (s1h >= 0.0) else min(abs(s1l), abs(s1h))
        m3 = max(abs(s3l), abs(s3h))
        n3 = 0.0 if (s3l <= 0.0) & (s3h >= 0.0) else min(abs(s3l), abs(s3h))
        c1 = n1 > m3  # |σ1| > |σ3| surely: σ1
        c3 = m1 < n3  # (else) σ3; neither: the sign choice open, both
        bl = s1l if c1 else (s3l if c3 else min(s1l, s3l))
        bh = s1h if c1 else (s3h if c3 else max(s1h, s3h))
        ok = t == t
        lo[j] = bl if ok else -np.inf
        hi[j] = bh if ok else np.inf
    ks = wa  # kept (1.0) or proven strictly monotone through (0.0); the ends kept
    if n > 0:
        ks[0] = 1.0
        ks[n - 1] = 1.0
    for j in range(1, n - 1):
        up0 = lo[j] > hi[j - 1]
        up1 = lo[j + 1] > hi[j]
        dn0 = hi[j] < lo[j - 1]
        dn1 = hi[j + 1] < lo[j]
        ks[j] = 0.0 if (up0 & up1) | (dn0 & dn1) else 1.0
    m = 0
    for j in range(n):
        if ks[j] != 0.0:
            for cc in range(6):
                out[cc, pos + m] = buf[cc, i, j]
            m += 1
    return m


def _keep_gather(buf, n, out, pos, counts, lo, hi, w):  # type: ignore[no-untyped-def]
    """buf (6, k, >= n): components; per node the kept samples' components appended to out
    (6, cap) node by node from column pos (:func:`_node_keep`; w its scratch), their
    number into counts (k,). Returns the end column, or -1 when out may be too small (a
    node starts with fewer than n columns left)."""
    k = buf.shape[1]
    for i in range(k):
        if pos + n > out.shape[1]:
            return -1
        m = _node_keep(buf, i, n, out, pos, lo, hi, w)
        counts[i] = m
        pos += m
    return pos


def _node_products(FT, coef, i, out, io):  # type: ignore[no-untyped-def]  # noqa: C901
    """out[:, io] (6, n) = the components of node i of coef (k, cases, 6) under loads FT
    (cases, n): per sample the sum in case order of the rounded products (no fused
    multiply-add: numba without fastmath), four cases per pass over the samples
    (:mod:`.superposition`)."""
    nc, n = FT.shape
    o0, o1, o2 = out[0, io], out[1, io], out[2, io]
    o3, o4, o5 = out[3, io], out[4, io], out[5, io]
    c = 0
    while c < nc:
        if nc - c >= 4:
            f0, f1, f2, f3 = FT[c], FT[c + 1], FT[c + 2], FT[c + 3]
            a0, a1, a2, a3 = coef[i, c], coef[i, c + 1], coef[i, c + 2], coef[i, c + 3]
            a00, a01, a02, a03, a04, a05 = a0[0], a0[1], a0[2], a0[3], a0[4], a0[5]
            a10, a11, a12, a13, a14, a15 = a1[0], a1[1], a1[2], a1[3], a1[4], a1[5]
            a20, a21, a22, a23, a24, a25 = a2[0], a2[1], a2[2], a2[3], a2[4], a2[5]
            a30, a31, a32, a33, a34, a35 = a3[0], a3[1], a3[2], a3[3], a3[4], a3[5]
            if c == 0:
                for j in range(n):
                    g0, g1, g2, g3 = f0[j], f1[j], f2[j], f3[j]
                    o0[j] = a00 * g0 + a10 * g1 + a20 * g2 + a30 * g3
                    o1[j] = a01 * g0 + a11 * g1 + a21 * g2 + a31 * g3
                    o2[j] = a02 * g0 + a12 * g1 + a22 * g2 + a32 * g3
                    o3[j] = a03 * g0 + a13 * g1 + a23 * g2 + a33 * g3
                    o4[j] = a04 * g0 + a14 * g1 + a24 * g2 + a34 * g3
                    o5[j] = a05 * g0 + a15 * g1 + a25 * g2 + a35 * g3
            else:
                for j in range(n):
                    g0, g1, g2, g3 = f0[j], f1[j], f2[j], f3[j]
                    o0[j] = o0[j] + a00 * g0 + a10 * g1 + a20 * g2 + a30 * g3
                    o1[j] = o1[j] + a01 * g0 + a11 * g1 + a21 * g2 + a31 * g3
                    o2[j] = o2[j] + a02 * g0 + a12 * g1 + a22 * g2 + a32 * g3
                    o3[j] = o3[j] + a03 * g0 + a13 * g1 + a23 * g2 + a33 * g3
                    o4[j] = o4[j] + a04 * g0 + a14 * g1 + a24 * g2 + a34 * g3
                    o5[j] = o5[j] + a05 * g0 + a15 * g1 + a25 * g2 + a35 * g3
            c += 4
        else:
            f0 = FT[c]
            a0 = coef[i, c]
            a00, a01, a02, a03, a04, a05 = a0[0], a0[1], a0[2], a0[3], a0[4], a0[5]
            if c == 0:
                for j in range(n):
                    g0 = f0[j]
                    o0[j] = a00 * g0
                    o1[j] = a01 * g0
                    o2[j] = a02 * g0
                    o3[j] = a03 * g0
                    o4[j] = a04 * g0
                    o5[j] = a05 * g0
            else:
                for j in range(n):
                    g0 = f0[j]
                    o0[j] = o0[j] + a00 * g0
                    o1[j] = o1[j] + a01 * g0
                    o2[j] = o2[j] + a02 * g0
                    o3[j] = o3[j] + a03 * g0
                    o4[j] = o4[j] + a04 * g0
                    o5[j] = o5[j] + a05 * g0
            c += 1


def _products(FT, coef, out):  # type: ignore[no-untyped-def]
    """out (6, k, n): :func:`_node_products` of every node of coef (k, cases, 6)."""
    for i in range(coef.shape[0]):
        _node_products(FT, coef, i, out, i)


def _sup_keep_gather(FT, coef, n, out, pos, counts, lo, hi, buf, w):  # type: ignore[no-untyped-def]  # noqa: E501
    """Per node of coef (k, cases, 6) the products into buf (6, 1, >= n) and its kept
    samples' components appended to out (6, cap) from column pos (:func:`_node_keep`, w
    its scratch; the node's stresses never leave the cache); counts (k,). Returns the end
    column, or -1 when out may be too small."""
    for i in range(coef.shape[0]):
        if pos + n > out.shape[1]:
            return -1
        _node_products(FT, coef, i, buf, 0)
        m = _node_keep(buf, 0, n, out, pos, lo, hi, w)
        counts[i] = m
        pos += m
    return pos


KERNELS = (("_root1", "UniTuple(f8, 2)(f8)"),
           ("_node_keep", "i8(f8[:, :, ::1], i8, i8, f8[:, ::1], i8, f8[::1], f8[::1], "
            "f8[:, ::1])"),
           ("_keep_gather",
            "i8(f8[:, :, ::1], i8, f8[:, ::1], i8, i8[::1], f8[::1], f8[::1], f8[:, ::1])"),
           ("_node_products", "void(f8[:, ::1], f8[:, :, ::1], i8, f8[:, :, ::1], i8)"),
           ("_products", "void(f8[:, ::1], f8[:, :, ::1], f8[:, :, ::1])"),
           ("_sup_keep_gather", "i8(f8[:, ::1], f8[:, :, ::1], i8, f8[:, ::1], i8, i8[::1], "
            "f8[::1], f8[::1], f8[:, :, ::1], f8[:, ::1])"))


def build() -> None:
    """Compile this module's kernels now (or load them from the cache; once)."""
    compile_kernels(globals(), KERNELS)


def kept_equivalent(buf: np.ndarray, n: int, kind: str, scratch: np.ndarray | None = None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """(``vals`` (K,), ``counts`` (k,)): node by node, the exact equivalent stress ``kind``
    of its kept samples in order (a superset of the turning points with the block's first
    and last samples), and how many per node. ``buf`` (6, k, >= n): stress components [Pa],
    C-contiguous (component, node, sample), of the block's ``n`` samples (the rest is
    padding; :func:`.superposition.components_buffer`); ``scratch``: a flat float64 array
    the kept components are gathered into (a larger one is allocated when they do not fit).
    """
    k = buf.shape[1]
    if kind != "abs_max_principal" or n <= 2:
        eq = equivalent_of(buf[:, :, :n].transpose(0, 2, 1), kind)  # (n, k)
        return np.ascontiguousarray(eq.T).ravel(), np.full(k, n, dtype=np.int64)
    counts = np.empty(k, dtype=np.int64)
    K = -1
    if scratch is not None and scratch.size >= 6 * n:
        K = gather_kept(buf, n, scratch[:scratch.size // 6 * 6].reshape(6, -1), 0, counts)
    if K < 0:  # no scratch, or too small for what this block keeps
        out = np.empty((6, k * n))
        K = gather_kept(buf, n, out, 0, counts)
    else:
        assert scratch is not None  # K >= 0: the scratch held the kept samples
        out = scratch[:scratch.size // 6 * 6].reshape(6, -1)
    return equivalent_of(out[:, :K], kind), counts


def gather_kept(buf: np.ndarray, n: int, out: np.ndarray, pos: int, counts: np.ndarray
                ) -> int:
    """The compiled pass of :func:`kept_equivalent` (abs-max principal, numba): the
    components of each node's samples that may be turning points (and the block's ends)
    appended to ``out`` (6, cap), C-contiguous, node by node from column ``pos``; how many
    per node into ``counts`` (k,). Returns the end column, or -1 when ``out`` may be too
    small (then nothing is promised about what was written from ``pos``)."""
    build()
    return int(_keep_gather(buf, n, out, pos, counts, np.empty(n), np.empty(n),
                            np.empty((6, n))))


def products_compiled(FT: np.ndarray, coef: np.ndarray, out: np.ndarray) -> None:
    """out (6, k, n) [Pa]: the stress components of nodes ``coef`` (k, cases, 6), C-contiguous,
    under loads ``FT`` (cases, n) [N, N m] (:mod:`.superposition`'s definition: per sample
    the sum in case order, no fused multiply-add; numba)."""
    build()
    _products(FT, coef, out)


def superpose_gather(F: np.ndarray, coef: np.ndarray, out: np.ndarray, counts: np.ndarray
                     ) -> int:
    """:func:`.superposition.components_buffer` and :func:`gather_kept` fused per node
    (numba; the same bits): the kept samples' components of nodes ``coef`` (k, cases, 6)
    under the block's loads ``F`` (n, cases) written to ``out`` (6, cap) node by node from
    column 0, how many per node into ``counts`` (k,). Returns the end column, or -1 when
    ``out`` may be too small (then nothing is promised about what was written)."""
    build()
    n = F.shape[0]
    FT = np.ascontiguousarray(F.T, dtype=float)
    buf = np.empty((6, 1, max(n, 1)))
    return int(_sup_keep_gather(FT, coef, n, out, 0, counts, np.empty(n), np.empty(n), buf,
                                np.empty((6, n))))
