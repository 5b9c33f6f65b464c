"""The screening bound of :class:`.screening.StressScreen`: its compiled kernels (numba).

:meth:`.screening.StressScreen.block` bounds the equivalent stress of a set of nodes over a
block of loads (envelope [lo, hi] and total variation TV, Pa) from per-sub-block statistics of
the loads. The bound (the module docstring of :mod:`.screening`, steps 1-2) is one pass per
node over the block's sub-blocks: the loads' statistics per sub-block are computed once in
numpy (:func:`load_stats`, a few (sub-blocks, cases) arrays), then per node and sub-block ~550
floating-point operations (the middle stress, the two deviation bounds R, their principal
stresses, the triangle and Cauchy-Schwarz sums), ~22 per node-sample against ~280 for the exact
path, with the node's coefficients in cache.

**Principal stresses without transcendentals, proven:** the largest root of 4c³ - 3c = r is
bracketed by :func:`.turning_eq._root1` (a polynomial proposal checked by the sign of the
cubic at the bracket's ends). The bound must hold for the *true* principal stresses of the
computed tensor, not the exact path's bits, so the rounding of q, p, det and r is covered
by a half-width ``BRACKET_REL`` x 2p + ``BRACKET_ABS`` x |q| (r's rounding, a few 1e-16,
moves the root by at most ~sqrt(|Δr|) < 1e-7 at the double root r = -1; q's and the
deviator's by a few ulp of |q|). The middle stress's own rounding (a sum of 15 products) is
below 1e-15 x max_c |F_c| x Σ|A|: the envelope is padded by ``ROUNDING_MARGIN`` (1e-9)
times that, |hi|, |lo| and Σ R; TV is raised by the same margin. The tests check the bound
against the exact envelope, variation and damage (any upper bound is a valid screen); a
non-finite tensor gives the node (+inf, -inf, +inf): never left out.

Kept apart from :mod:`.screening` (the damage bound and the rule): these kernels are written
for LLVM's vectoriser (flat scratch rows, inlined scalar helpers), ~400 lines on their own.
"""

from __future__ import annotations

import threading

import numpy as np

from .counting import COMPILE_S, compile_kernels
from .turning_eq import _root1  # noqa: F401  (compiled with this module's kernels)

BRACKET_REL = 1e-6
"""Half-width of a principal stress's bracket per unit of 2p (see the module docstring)."""
BRACKET_ABS = 1e-12
"""Half-width of a principal stress's bracket per unit of |q| (rounding of q, deviator)."""
_LOCK = threading.Lock()
MARGIN = 1e-9
""":data:`.screening.ROUNDING_MARGIN` (relative padding of the envelope and TV)."""


def _principal(s0, s1, s2, s3, s4, s5):  # type: ignore[no-untyped-def]
    """Proven brackets (σ1 lo, σ1 hi, σ3 lo, σ3 hi) (Pa) of the largest and smallest
    principal stresses of the tensor (σx σy σz τxy τyz τzx)."""
    q = (s0 + s1 + s2) / 3.0
    a = s0 - q
    b = s1 - q
    c = s2 - q
    p = np.sqrt((a * a + b * b + c * c + 2.0 * (s3 * s3 + s4 * s4 + s5 * s5)) / 6.0)
    two_p = 2.0 * p
    t = BRACKET_REL * two_p + BRACKET_ABS * abs(q)
    det = a * b * c + 2.0 * s3 * s4 * s5 - a * s4 * s4 - b * s5 * s5 - c * s3 * s3
    tiny = not (p > 1e-90)  # (or NaN): c in [-1, 1]
    pp = _sel(tiny, 1.0, p)
    r = det / (pp * pp * pp * 2.0)
    r = _sel(r > 1.0, 1.0, _sel(r < -1.0, -1.0, r))
    l1, h1 = _root1(r)
    l3, h3 = _root1(-r)
    l1 = _sel(tiny, -1.0, l1)
    h1 = _sel(tiny, 1.0, h1)
    l3 = _sel(tiny, -1.0, l3)
    h3 = _sel(tiny, 1.0, h3)
    return q + two_p * l1 - t, q + two_p * h1 + t, q - two_p * h3 - t, q - two_p * l3 + t


def _sel(c, a, b):  # type: ignore[no-untyped-def]
    """a where c else b (a select: keeps the node loops vectorisable)."""
    return a if c else b


CHUNK = 32
"""Nodes bounded at a time (their gathered table 32 x ~3.5 kB stays in L2; measured best
of 8-64). A compile-time constant of the kernels: the scratch rows are CHUNK apart, so
LLVM sees their distances and vectorises the node loops without runtime alias checks."""
_S, _HR, _ZR, _RH, _HB, _LB, _BAD, _JMP, _WT, _T1, _T2 = (
    0, 6, 12, 18, 19, 20, 21, 22, 23, 24, 25)
"""Rows of the flat scratch (x CHUNK): the middle stress (6), the two deviation bounds
(6 + 6), the hydrostatic half range, the envelope, the non-finite flag, the sub-block's
jumps and variation weight, the two triangle sums."""
ROWS = 26


def _tail(br1, br3, hi1, lo1, hi3, lo3, jump, sum_r, tot, mc, n_i):  # type: ignore[no-untyped-def]  # noqa: E501
    """One node-sub-block: its padded envelope (hi, lo), non-finite flag, jumps and
    variation weight (scalars only: no array in an inlined helper, no reference count in
    the node loop, which LLVM could not vectorise)."""
    hi = max(_sel(br1, hi1, -np.inf), _sel(br3, hi3, -np.inf))
    lo = min(_sel(br1, lo1, np.inf), _sel(br3, lo3, np.inf))
    pad = MARGIN * (abs(hi) + abs(lo) + sum_r + mc)
    both = br1 & br3
    return (hi + pad, lo - pad, _sel(tot - tot == 0.0, 0.0, 1.0), _sel(both, n_i * jump, 0.0),
            _sel(both, 2.0, 1.0))


def _bound_chunk(X, B, M, H, ZH, Mmax, tvF, tvZ, nin, vm, o, w, tv):  # type: ignore[no-untyped-def]  # noqa: C901, E501
    """Nodes 0..B-1 of the gathered table X (width, CHUNK; offsets ``o`` of
    :class:`NodeTables`) over every sub-block j: envelope into the rows _HB, _LB of the
    flat scratch w (ROWS x CHUNK), TV into tv, non-finite into _BAD. Every inner loop
    runs over the nodes (SIMD)."""
    nc = M.shape[1]
    C = CHUNK
    oC, oA, oV, oNA, oNAV, oT, oS = o[0], o[1], o[2], o[3], o[4], o[5], o[6]
    for b in range(CHUNK):
        w[_HB * C + b] = -np.inf
        w[_LB * C + b] = np.inf
        w[_BAD * C + b] = 0.0
        tv[b] = 0.0
    for j in range(M.shape[0]):
        for b in range(_RH * C):
            w[b] = 0.0
        for c in range(nc):
            m = M[j, c]
            h = H[j, c]
            z = ZH[j, c]
            for u in range(6):
                xc = X[oC + 6 * c + u]
                xa = X[oA + 6 * c + u]
                xv = X[oV + 6 * c + u]
                for b in range(CHUNK):
                    w[(_S + u) * C + b] += m * xc[b]
                    w[(_HR + u) * C + b] += h * xa[b]
                    w[(_ZR + u) * C + b] += z * xv[b]
        n_i = nin[j]
        mm = Mmax[j]
        xs = X[oS]
        if vm == 0:  # abs-max principal
            for b in range(CHUNK):
                r0 = min(w[6 * C + b], w[12 * C + b])
                r1 = min(w[7 * C + b], w[13 * C + b])
                r2 = min(w[8 * C + b], w[14 * C + b])
                r3 = min(w[9 * C + b], w[15 * C + b])
                r4 = min(w[10 * C + b], w[16 * C + b])
                r5 = min(w[11 * C + b], w[17 * C + b])
                s0 = w[b]
                s1 = w[C + b]
                s2 = w[2 * C + b]
                s3 = w[3 * C + b]
                s4 = w[4 * C + b]
                s5 = w[5 * C + b]
                a1l, a1h, a3l, a3h = _principal(s0, s1, s2, s3, s4, s5)
                rho = max(_principal(r0, r1, r2, r3, r4, r5)[1], 0.0)
                br1 = a1h + a3h + 2.0 * rho >= 0.0
                br3 = a1l + a3l - 2.0 * rho < 0.0
                jump = 2.0 * (min(max(abs(a1l), abs(a1h)), max(abs(a3l), abs(a3h))) + rho)
                sum_r = r0 + r1 + r2 + r3 + r4 + r5
                t = _tail(br1, br3, a1h + rho, max(a1l - rho, 0.0), min(a3h + rho, 0.0),
                      a3l - rho, jump, sum_r, s0 + s1 + s2 + s3 + s4 + s5 + sum_r,
                      mm * xs[b], n_i)
                w[_HB * C + b] = max(w[_HB * C + b], t[0])
                w[_LB * C + b] = min(w[_LB * C + b], t[1])
                w[_BAD * C + b] = max(w[_BAD * C + b], t[2])
                w[_JMP * C + b] = t[3]
                w[_WT * C + b] = t[4]
        else:  # signed von Mises: vm² = sᵀ Q s, R |Q| R, the hydrostatic interval
            for b in range(CHUNK):
                w[_RH * C + b] = 0.0
            for c in range(nc):
                h = H[j, c]
                xt = X[oT + c]
                for b in range(CHUNK):
                    w[_RH * C + b] += h * xt[b]
            for b in range(CHUNK):
                r0 = min(w[6 * C + b], w[12 * C + b])
                r1 = min(w[7 * C + b], w[13 * C + b])
                r2 = min(w[8 * C + b], w[14 * C + b])
                r3 = min(w[9 * C + b], w[15 * C + b])
                r4 = min(w[10 * C + b], w[16 * C + b])
                r5 = min(w[11 * C + b], w[17 * C + b])
                s0 = w[b]
                s1 = w[C + b]
                s2 = w[2 * C + b]
                s3 = w[3 * C + b]
                s4 = w[4 * C + b]
                s5 = w[5 * C + b]
                d01 = s0 - s1
                d12 = s1 - s2
                d20 = s2 - s0
                v = np.sqrt(max(0.5 * (d01 * d01 + d12 * d12 + d20 * d20)
                                + 3.0 * (s3 * s3 + s4 * s4 + s5 * s5), 0.0))
                rv = np.sqrt(r0 * r0 + r1 * r1 + r2 * r2 + r0 * r1 + r1 * r2 + r2 * r0
                             + 3.0 * (r3 * r3 + r4 * r4 + r5 * r5))
                hh = (s0 + s1 + s2) / 3.0
                rh = w[_RH * C + b]
                lo1 = max(v - rv, 0.0)
                sum_r = r0 + r1 + r2 + r3 + r4 + r5
                t = _tail(hh + rh >= 0.0, hh - rh < 0.0, v + rv, lo1, -lo1, -(v + rv),
                      2.0 * (v + rv), sum_r, s0 + s1 + s2 + s3 + s4 + s5 + sum_r,
                      mm * xs[b], n_i)
                w[_HB * C + b] = max(w[_HB * C + b], t[0])
                w[_LB * C + b] = min(w[_LB * C + b], t[1])
                w[_BAD * C + b] = max(w[_BAD * C + b], t[2])
                w[_JMP * C + b] = t[3]
                w[_WT * C + b] = t[4]
        if n_i > 0.0:
            for b in range(_T1 * C, (_T2 + 1) * C):
                w[b] = 0.0
            for c in range(nc):
                f = tvF[j, c]
                z = tvZ[j, c]
                xa = X[oNA + c]
                xv = X[oNAV + c]
                for b in range(CHUNK):
                    w[_T1 * C + b] += f * xa[b]
                    w[_T2 * C + b] += z * xv[b]
            for b in range(CHUNK):
                sum_n = min(w[_T1 * C + b], w[_T2 * C + b])
                tv[b] += w[_WT * C + b] * sum_n + w[_JMP * C + b]


def _bound_nodes(idx, T, M, H, ZH, Mmax, tvF, tvZ, nin, vm, o, X, w, hi_out, lo_out,  # type: ignore[no-untyped-def]  # noqa: E501
                 tv_out):
    """Per node idx[k] (rows of the node table T): envelope and TV bound over the block
    (:func:`_bound_chunk`), CHUNK nodes at a time gathered into X (width, CHUNK)
    (node-innermost, for SIMD)."""
    W = T.shape[1]
    C = CHUNK
    tv = np.empty(C)
    for k0 in range(0, idx.size, C):
        B = min(C, idx.size - k0)
        for b in range(C):  # a short last chunk: its last node again (results unused)
            row = T[idx[k0 + min(b, B - 1)]]
            for u in range(W):
                X[u, b] = row[u]
        _bound_chunk(X, B, M, H, ZH, Mmax, tvF, tvZ, nin, vm, o, w, tv)
        for b in range(B):
            hb = w[_HB * C + b]
            lb = w[_LB * C + b]
            ok = w[_BAD * C + b] == 0.0 and hb - hb == 0.0 and lb - lb == 0.0 \
                and tv[b] - tv[b] == 0.0
            hi_out[k0 + b] = hb if ok else np.inf
            lo_out[k0 + b] = lb if ok else -np.inf
            tv_out[k0 + b] = tv[b] * (1.0 + MARGIN) if ok else np.inf


def _bound_slots(Xs, m, M, H, ZH, Mmax, tvF, tvZ, nin, vm, o, w, hi_out, lo_out,  # type: ignore[no-untyped-def]  # noqa: E501
                 tv_out):
    """:func:`_bound_nodes` for the first m slots of the kept chunks Xs (chunks, width,
    CHUNK) (:meth:`NodeTables.bounds_kept`: no gather), results by slot."""
    C = CHUNK
    tv = np.empty(C)
    for ch in range((m + C - 1) // C):
        B = min(C, m - ch * C)
        _bound_chunk(Xs[ch], B, M, H, ZH, Mmax, tvF, tvZ, nin, vm, o, w, tv)
        k0 = ch * C
        for b in range(B):
            hb = w[_HB * C + b]
            lb = w[_LB * C + b]
            ok = w[_BAD * C + b] == 0.0 and hb - hb == 0.0 and lb - lb == 0.0 \
                and tv[b] - tv[b] == 0.0
            hi_out[k0 + b] = hb if ok else np.inf
            lo_out[k0 + b] = lb if ok else -np.inf
            tv_out[k0 + b] = tv[b] * (1.0 + MARGIN) if ok else np.inf


_A3 = "f8[:, :, ::1]"
_A2 = "f8[:, ::1]"
INLINE = ("_sel", "_principal", "_tail")
"""Helpers inlined into the kernels (numba ``inline="always"``: the node loops stay
straight-line code that LLVM vectorises; a call per node-sub-block would not)."""
_F1 = "f8[::1]"
_STATS = f"{_A2}, {_A2}, {_A2}, {_F1}, {_A2}, {_A2}, {_F1}, i8, i8[::1]"
"""M, H, ZH, Mmax, tvF, tvZ, nin (:func:`load_stats`), vm, offsets."""
KERNELS = (("_bound_chunk", f"void({_A2}, i8, {_STATS}, {_F1}, {_F1})"),
           ("_bound_nodes", f"void(i8[::1], {_A2}, {_STATS}, {_A2}, {_F1}, {_F1}, {_F1}, "
            f"{_F1})"),
           ("_bound_slots", f"void({_A3}, i8, {_STATS}, {_F1}, {_F1}, {_F1}, {_F1})"))


def build() -> None:
    """Compile this module's kernels now (or load them from numba's cache; once)."""
    from . import turning_eq

    g = globals()
    if __name__ not in COMPILE_S:
        import numba

        turning_eq.build()
        with _LOCK:
            if not hasattr(g["_sel"], "py_func"):
                root = getattr(turning_eq._root1, "py_func", turning_eq._root1)
                g["_root1"] = numba.njit(inline="always")(root)
                for fn in INLINE:
                    g[fn] = numba.njit(inline="always")(g[fn])
    compile_kernels(g, KERNELS)


def load_stats(Fe: np.ndarray, V: np.ndarray, sub_samples: int) -> dict[str, np.ndarray]:
    """The loads' statistics per sub-block of ``sub_samples`` increments (N, N m; the
    quantities of :meth:`.screening.StressScreen.block`): middle M, half range H, the
    half range ZH along the principal axes V about M, max |M|, the increments' absolute
    sums tvF and tvZ and the number of increments nin. ``Fe`` (n_e, cases): the block
    with the previous block's last sample first."""
    n_e, nc = Fe.shape
    L = max(1, int(sub_samples))
    starts = np.arange(0, max(n_e - 1, 1), L)
    stops = np.minimum(starts + L + 1, n_e)
    J = starts.size
    Z = Fe @ V
    M = np.empty((J, nc))
    H = np.empty((J, nc))
    ZH = np.empty((J, nc))
    for j, (a, b) in enumerate(zip(starts, stops, strict=True)):
        lo, hi = Fe[a:b].min(axis=0), Fe[a:b].max(axis=0)
        M[j] = 0.5 * (lo + hi)
        H[j] = 0.5 * (hi - lo)
        mz = M[j] @ V
        ZH[j] = np.maximum(Z[a:b].max(axis=0) - mz, mz - Z[a:b].min(axis=0))
    if n_e < 2:
        z = np.zeros((J, nc))
        return {"M": M, "H": H, "ZH": ZH, "Mmax": np.abs(M).max(axis=1), "tvF": z,
                "tvZ": z, "nin": np.zeros(J)}
    dF = np.diff(Fe, axis=0)
    tvF = np.add.reduceat(np.abs(dF), starts, axis=0)
    tvZ = np.add.reduceat(np.abs(np.diff(Z, axis=0)), starts, axis=0)
    return {"M": M, "H": H, "ZH": np.ascontiguousarray(ZH), "Mmax": np.abs(M).max(axis=1),
            "tvF": tvF, "tvZ": tvZ,
            "nin": (stops - starts - 1).astype(float)}


class NodeTables:
    """The compiled bound's per-node table, one row a node (node-major): A (cases x 6),
    |A|, |A V|, the norms N(A_c), N(A v_m), |tr A_c|/3 and Σ|A| (436 -> 316 doubles a node
    without the Cauchy-Schwarz form G: the table is read from memory once a block);
    ``offsets`` where each starts in a row."""

    def __init__(self, C: np.ndarray, NA: np.ndarray, abs_tr3: np.ndarray) -> None:
        nc, n, _ = C.shape
        Cn = C.transpose(1, 0, 2).reshape(n, -1)
        widths = [6 * nc, 6 * nc, 6 * nc, nc, nc, nc, 1]
        self.offsets = np.cumsum([0] + widths[:-1]).astype(np.int64)
        o = self.offsets
        self.T = np.empty((n, sum(widths)))
        self.T[:, o[0]:o[1]] = Cn
        np.abs(Cn, out=self.T[:, o[1]:o[2]])
        self.T[:, o[3]:o[4]] = NA.T
        self.T[:, o[5]:o[6]] = abs_tr3.T
        self.T[:, o[6]] = self.T[:, o[1]:o[2]].sum(axis=1)
        self.T[:, o[2]:o[3]] = np.inf  # until set_axes: no tighter bound along them
        self.T[:, o[4]:o[5]] = np.inf
        self.slot_node = np.zeros(0, dtype=np.int64)
        """The node in each kept slot (:meth:`bounds_kept`)."""
        self.node_slot = np.full(n, -1, dtype=np.int64)
        self.Xs = np.zeros((-(-n // CHUNK), self.T.shape[1], CHUNK))
        """Kept nodes' table columns, CHUNK nodes a chunk (node-innermost, as gathered;
        room for every node, its pages touched only as nodes are kept)."""

    def set_axes(self, CV: np.ndarray, NAV: np.ndarray) -> None:
        """The loads' principal axes' columns: |A V| (axes, n, 6), N(A v_m) (axes, n)."""
        o, n = self.offsets, self.T.shape[0]
        self.T[:, o[2]:o[3]] = np.abs(CV).transpose(1, 0, 2).reshape(n, -1)
        self.T[:, o[4]:o[5]] = NAV.T
        self.slot_node = np.zeros(0, dtype=np.int64)  # kept columns are stale now
        self.node_slot[:] = -1

    def _keep(self, idx: np.ndarray) -> None:
        """Make the kept slots hold exactly the nodes ``idx`` (any order): a node that
        left is replaced by one from the end, new nodes appended (their columns written
        once, not gathered every block)."""
        n = self.node_slot.size
        want = np.zeros(n, dtype=bool)
        want[idx] = True
        gone = np.nonzero(~want[self.slot_node])[0]  # their slots
        new = np.nonzero(want & (self.node_slot < 0))[0]
        m = self.slot_node.size - gone.size
        if gone.size:
            tail = np.arange(m, self.slot_node.size)
            movers = tail[want[self.slot_node[tail]]]  # kept nodes beyond the new end
            holes = np.sort(gone)[:movers.size]  # gone slots below the new end
            self.node_slot[self.slot_node[gone]] = -1
            if movers.size:
                self.Xs[holes // CHUNK, :, holes % CHUNK] = \
                    self.Xs[movers // CHUNK, :, movers % CHUNK]
                self.slot_node[holes] = self.slot_node[movers]
                self.node_slot[self.slot_node[holes]] = holes
            self.slot_node = self.slot_node[:m]
        if new.size:
            total = m + new.size
            slots = np.arange(m, total)
            self.Xs[slots // CHUNK, :, slots % CHUNK] = self.T[new]
            self.slot_node = np.concatenate([self.slot_node, new])
            self.node_slot[new] = slots

    def bounds_kept(self, stats: dict[str, np.ndarray], idx: np.ndarray, von_mises: bool
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`bounds` of nodes ``idx`` (distinct) kept in slots between calls: for a
        set that changes little from block to block (the left-out nodes)."""
        build()
        self._keep(idx)
        m = self.slot_node.size
        hi, lo, tv = np.empty(m), np.empty(m), np.empty(m)
        s = stats
        _bound_slots(self.Xs, m, s["M"], s["H"], s["ZH"], s["Mmax"], s["tvF"], s["tvZ"],
                     s["nin"], int(von_mises), self.offsets, np.empty(ROWS * CHUNK),
                     hi, lo, tv)
        at = self.node_slot[idx]
        return hi[at], lo[at], tv[at]

    def bounds(self, stats: dict[str, np.ndarray], idx: np.ndarray, von_mises: bool
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(hi, lo, tv) (Pa) of nodes ``idx`` over the block of ``stats``."""
        build()
        idx = np.ascontiguousarray(idx, dtype=np.int64)
        hi, lo, tv = np.empty(idx.size), np.empty(idx.size), np.empty(idx.size)
        s = stats
        X = np.empty((self.T.shape[1], CHUNK))
        w = np.empty(ROWS * CHUNK)
        _bound_nodes(idx, self.T, s["M"], s["H"], s["ZH"], s["Mmax"], s["tvF"], s["tvZ"],
                     s["nin"], int(von_mises), self.offsets, X, w, hi, lo, tv)
        return hi, lo, tv
