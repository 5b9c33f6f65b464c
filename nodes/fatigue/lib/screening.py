"""Screening: an upper bound of each node's Miner damage from the loads' block statistics.

Computing a node's damage exactly costs its stresses at every sample (superposition, the
equivalent stress, rainflow); this module bounds it from what a block of loads gives for all
nodes at once, so that a node whose bound stays below a stated fraction of the damage already
reached need not be computed (:mod:`.worker`). Symbols: A_c a node's influence coefficients
(σx σy σz τxy τyz τzx, Pa per N or N m) of load case c, F_c the loads (N, N m), stress
σ = Σ_c A_c F_c; e_k the equivalent stress (Pa; abs-max principal or signed von Mises) at
sample k. Per block and node (:class:`StressScreen`, per sub-block of :data:`SUB_SAMPLES`
loads): the envelope [lo, hi] of e and a bound of its total variation TV = Σ_k |e_k - e_(k-1)|
(Pa). Over the history (envelope [LO, HI]) the damage D <= g (TV + (HI - LO)/2)
(:func:`damage_bound`; g (1/Pa) :func:`.damage.damage_per_range`, for the laws it accepts).
Source: derived for this project from Weyl's inequality, Perron-Frobenius and rainflow's
four-point rule: docs/live_fatigue.md, "The screening bound", with the rounding margins
(:data:`BRACKET_REL`, :data:`BRACKET_ABS`, :data:`ROUNDING_MARGIN`) that keep it above the
true principal stresses of the computed tensors. It holds for every history (tested against
exact counts; a non-finite tensor gives (+inf, -inf, +inf): never left out); it is not tight,
which only costs how many nodes are screened out, never a wrong result. The kernels
(:func:`_bound_chunk`, after :func:`load_stats` in numpy) take ~550 flops per node and
sub-block, :data:`CHUNK` nodes at a time, written for LLVM's vectoriser (~1.8 ns per
node-sample against 11-14 for the exact path).
"""

from __future__ import annotations

import numpy as np

from . import turning_eq
from .counting import compile_kernels
from .damage import damage_per_range
from .material import Material
from .turning_eq import _root1  # noqa: F401  (compiled with this module's kernels)

TOP_NODES = 10
"""The reported most damaged nodes (``summary.json`` ``top_nodes``): never screened out."""
ROUNDING_MARGIN = 1e-9
SUB_SAMPLES = 25
BRACKET_REL = 1e-6
"""Half-width of a principal stress's bracket per unit of 2p (covers r's rounding)."""
BRACKET_ABS = 1e-12
"""Half-width of a principal stress's bracket per unit of |q| (rounding of q, deviator)."""
_FROB = np.array([1.0, 1.0, 1.0, 2.0, 2.0, 2.0])
"""Frobenius norm² of a symmetric tensor from its 6 components (σx σy σz τxy τyz τzx)."""
_VM = np.diag([1.5, 1.5, 1.5, 3.0, 3.0, 3.0]) - 0.5 * np.pad(np.ones((3, 3)), (0, 3))
"""vm² = sᵀ Q s (von Mises, 6 components)."""


def _principal(s0, s1, s2, s3, s4, s5):  # type: ignore[no-untyped-def]
    """Proven brackets (σ1 lo, σ1 hi, σ3 lo, σ3 hi) (Pa) of the largest and smallest
    principal stresses of the tensor (σx σy σz τxy τyz τzx)."""
    q = (s0 + s1 + s2) / 3.0
    a, b, c = s0 - q, s1 - q, s2 - q
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
    l1, h1 = _sel(tiny, -1.0, l1), _sel(tiny, 1.0, h1)
    l3, h3 = _sel(tiny, -1.0, l3), _sel(tiny, 1.0, h3)
    return q + two_p * l1 - t, q + two_p * h1 + t, q - two_p * h3 - t, q - two_p * l3 + t


def _sel(c, a, b):  # type: ignore[no-untyped-def]
    """a where c else b (a select: keeps the node loops vectorisable)."""
    return a if c else b


CHUNK = 32
"""Nodes bounded at a time (measured best of 8-64); a compile-time constant, so LLVM sees the
scratch rows' distances and vectorises the node loops without runtime alias checks."""
_S, _HR, _ZR, _RH, _HB, _LB, _BAD, _JMP, _WT, _T1, _T2 = (
    0, 6, 12, 18, 19, 20, 21, 22, 23, 24, 25)
"""Rows of the flat scratch (x CHUNK): the middle stress (6), the two deviation bounds
(6 + 6), the hydrostatic half range, the envelope, the non-finite flag, the sub-block's
jumps and variation weight, the two triangle sums."""
ROWS = 26


def _bound_chunk(X, M, H, ZH, Mmax, tvF, tvZ, nin, vm, o, w, tv):  # type: ignore[no-untyped-def]  # noqa: C901, E501
    """The CHUNK nodes of the table X (width, CHUNK; offsets ``o``) over every sub-block:
    envelope into the rows _HB, _LB of the scratch w (ROWS x CHUNK), TV into tv, non-finite
    into _BAD. Every inner loop runs over the nodes (SIMD)."""
    nc = M.shape[1]
    C = CHUNK
    oC, oA, oV, oNA, oNAV, oT, oS = o[0], o[1], o[2], o[3], o[4], o[5], o[6]
    for b in range(CHUNK):
        w[_HB * C + b] = -np.inf
        w[_LB * C + b] = np.inf
        w[_BAD * C + b] = 0.0
        tv[b] = 0.0
    for j in range(M.shape[0]):
        for b in range(_RH * C + C):
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
            if vm != 0:  # the hydrostatic half range
                xt = X[oT + c]
                for b in range(CHUNK):
                    w[_RH * C + b] += h * xt[b]
        n_i = nin[j]
        mm = Mmax[j]
        xs = X[oS]
        for b in range(CHUNK):
            r0, r1, r2 = (min(w[6 * C + b], w[12 * C + b]), min(w[7 * C + b], w[13 * C + b]),
                          min(w[8 * C + b], w[14 * C + b]))
            r3, r4, r5 = (min(w[9 * C + b], w[15 * C + b]), min(w[10 * C + b], w[16 * C + b]),
                          min(w[11 * C + b], w[17 * C + b]))
            s0, s1, s2 = w[b], w[C + b], w[2 * C + b]
            s3, s4, s5 = w[3 * C + b], w[4 * C + b], w[5 * C + b]
            sum_r = r0 + r1 + r2 + r3 + r4 + r5
            tot = s0 + s1 + s2 + s3 + s4 + s5 + sum_r
            if vm == 0:  # abs-max principal: the branches σ1 (br1) and σ3 (br3)
                a1l, a1h, a3l, a3h = _principal(s0, s1, s2, s3, s4, s5)
                rho = max(_principal(r0, r1, r2, r3, r4, r5)[1], 0.0)
                jump = 2.0 * (min(max(abs(a1l), abs(a1h)), max(abs(a3l), abs(a3h))) + rho)
                br1, br3 = a1h + a3h + 2.0 * rho >= 0.0, a1l + a3l - 2.0 * rho < 0.0
                hi1, lo1, hi3, lo3 = a1h + rho, max(a1l - rho, 0.0), min(a3h + rho, 0.0), a3l - rho
            else:  # signed von Mises: vm² = sᵀ Q s, R |Q| R, the hydrostatic interval
                d01, d12, d20 = s0 - s1, s1 - s2, s2 - s0
                v = np.sqrt(max(0.5 * (d01 * d01 + d12 * d12 + d20 * d20)
                                + 3.0 * (s3 * s3 + s4 * s4 + s5 * s5), 0.0))
                rv = np.sqrt(r0 * r0 + r1 * r1 + r2 * r2 + r0 * r1 + r1 * r2 + r2 * r0
                             + 3.0 * (r3 * r3 + r4 * r4 + r5 * r5))
                hh = (s0 + s1 + s2) / 3.0
                rh = w[_RH * C + b]
                lo1 = max(v - rv, 0.0)
                br1, br3, jump = hh + rh >= 0.0, hh - rh < 0.0, 2.0 * (v + rv)
                hi1, hi3, lo3 = v + rv, -lo1, -(v + rv)
            # the padded envelope, the non-finite flag, the jumps and variation weight
            hi = max(_sel(br1, hi1, -np.inf), _sel(br3, hi3, -np.inf))
            lo = min(_sel(br1, lo1, np.inf), _sel(br3, lo3, np.inf))
            pad = ROUNDING_MARGIN * (abs(hi) + abs(lo) + sum_r + mm * xs[b])
            both = br1 & br3
            w[_HB * C + b] = max(w[_HB * C + b], hi + pad)
            w[_LB * C + b] = min(w[_LB * C + b], lo - pad)
            w[_BAD * C + b] = max(w[_BAD * C + b], _sel(tot - tot == 0.0, 0.0, 1.0))
            w[_JMP * C + b] = _sel(both, n_i * jump, 0.0)
            w[_WT * C + b] = _sel(both, 2.0, 1.0)
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


def _bound_slots(Xs, m, M, H, ZH, Mmax, tvF, tvZ, nin, vm, o, w, hi_out, lo_out,  # type: ignore[no-untyped-def]  # noqa: E501
                 tv_out):
    """:func:`_bound_chunk` of the first m slots of the chunks Xs, results by slot."""
    C = CHUNK
    tv = np.empty(C)
    for ch in range((m + C - 1) // C):
        B = min(C, m - ch * C)
        _bound_chunk(Xs[ch], M, H, ZH, Mmax, tvF, tvZ, nin, vm, o, w, tv)
        k0 = ch * C
        for b in range(B):
            hb = w[_HB * C + b]
            lb = w[_LB * C + b]
            ok = w[_BAD * C + b] == 0.0 and (hb - hb) + (lb - lb) + (tv[b] - tv[b]) == 0.0
            hi_out[k0 + b] = hb if ok else np.inf
            lo_out[k0 + b] = lb if ok else -np.inf
            tv_out[k0 + b] = tv[b] * (1.0 + ROUNDING_MARGIN) if ok else np.inf


_A2 = "f8[:, ::1]"
_F1 = "f8[::1]"
_STATS = f"{_A2}, {_A2}, {_A2}, {_F1}, {_A2}, {_A2}, {_F1}, i8, i8[::1]"
"""M, H, ZH, Mmax, tvF, tvZ, nin (:func:`load_stats`), vm, offsets."""
KERNELS = (("_bound_chunk", f"void({_A2}, {_STATS}, {_F1}, {_F1})"),
           ("_bound_slots", f"void(f8[:, :, ::1], i8, {_STATS}, {_F1}, {_F1}, {_F1}, {_F1})"))
INLINE = ("_root1", "_sel", "_principal")
"""Helpers inlined into the kernels: the node loops stay straight code LLVM vectorises."""


def build() -> None:
    """Compile this module's kernels now (or load them from numba's cache; once)."""
    turning_eq.build()
    compile_kernels(globals(), KERNELS, INLINE)


LoadStats = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                  np.ndarray]


def load_stats(Fe: np.ndarray, V: np.ndarray, sub_samples: int) -> LoadStats:
    """Per sub-block of ``sub_samples`` increments of ``Fe`` (n_e, cases; N, N m): middle M,
    half range H, half range ZH along the principal axes V about M, max |M|, the increments'
    absolute sums tvF, tvZ and their number nin (the kernels' arguments in that order)."""
    n_e, nc = Fe.shape
    L = max(1, int(sub_samples))
    starts = np.arange(0, max(n_e - 1, 1), L)
    stops = np.minimum(starts + L + 1, n_e)
    J = starts.size
    Z = Fe @ V
    M, H, ZH = np.empty((J, nc)), np.empty((J, nc)), np.empty((J, nc))
    for j, (a, b) in enumerate(zip(starts, stops, strict=True)):
        lo, hi = Fe[a:b].min(axis=0), Fe[a:b].max(axis=0)
        M[j] = 0.5 * (lo + hi)
        H[j] = 0.5 * (hi - lo)
        mz = M[j] @ V
        ZH[j] = np.maximum(Z[a:b].max(axis=0) - mz, mz - Z[a:b].min(axis=0))
    if n_e < 2:
        tvF = tvZ = np.zeros((J, nc))
        nin = np.zeros(J)
    else:
        tvF = np.add.reduceat(np.abs(np.diff(Fe, axis=0)), starts, axis=0)
        tvZ = np.add.reduceat(np.abs(np.diff(Z, axis=0)), starts, axis=0)
        nin = (stops - starts - 1).astype(float)
    return M, H, np.ascontiguousarray(ZH), np.abs(M).max(axis=1), tvF, tvZ, nin


class StressScreen:
    """The envelope [lo, hi] and total variation TV of the equivalent stress of any set of
    nodes over a block of loads, from the loads alone. The kernels' per-node table :attr:`T`,
    a row a node: A (cases x 6), |A|, |A V|, the norms N(A_c), N(A v_m), |tr A_c|/3 and Σ|A|
    (316 doubles a node); :attr:`offsets` where each starts."""

    def __init__(self, coefficients: np.ndarray, equivalent: str) -> None:
        C = np.asarray(coefficients, dtype=float)
        nc, n, _ = C.shape
        self.n = n
        self.C = C  # (cases, n, 6)
        self.kind = equivalent
        self.Q = np.diag(_FROB) if equivalent == "abs_max_principal" else _VM
        self.V: np.ndarray | None = None
        Cn = C.transpose(1, 0, 2).reshape(n, -1)
        un = np.full((n, 7 * nc), np.inf)  # |A V|, N(A v_m) until set_axes: no tighter bound
        cols = [Cn, np.abs(Cn), un[:, :6 * nc], self._norms(C).T, un[:, 6 * nc:],
                (np.abs(C[:, :, 0] + C[:, :, 1] + C[:, :, 2]) / 3.0).T,
                np.abs(Cn).sum(axis=1)[:, None]]
        self.T = np.concatenate(cols, axis=1)
        self.offsets = np.cumsum([0] + [c.shape[1] for c in cols[:-1]]).astype(np.int64)
        self.slot_node = np.zeros(0, dtype=np.int64)  # the node in each kept slot
        self.node_slot = np.full(n, -1, dtype=np.int64)
        self.Xs = np.zeros((-(-n // CHUNK), self.T.shape[1], CHUNK))
        """Kept nodes' table columns, CHUNK nodes a chunk (node-innermost; room for all)."""

    def block(self, Fe: np.ndarray, idx: np.ndarray, sub_samples: int,
              probe: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(hi, lo, tv) of nodes ``idx`` (then ``probe``'s) over ``Fe`` (n_e, cases): the
        block's loads with the previous block's last sample first (TV covers its n_e - 1
        increments)."""
        if self.V is None:
            self.set_axes(Fe)
        assert self.V is not None
        stats = load_stats(np.asarray(Fe, dtype=float), self.V, sub_samples)
        vm = self.kind != "abs_max_principal"
        both = idx if probe is None else np.concatenate([idx, probe])
        return self.bounds_kept(stats, both.astype(np.int64), vm)

    def _norms(self, C: np.ndarray) -> np.ndarray:
        """N of each case's stress tensor per node: (cases, n)."""
        return np.sqrt(np.maximum(((C @ self.Q) * C).sum(axis=2), 0.0))

    def set_axes(self, F: np.ndarray) -> None:
        """Principal axes V of a block of loads (the first; correlated loads bound much tighter
        along them than channel by channel) and the table's columns |A V|, N(A v_m)."""
        X = np.asarray(F, dtype=float)
        X = X - X.mean(axis=0)
        _, V = np.linalg.eigh(X.T @ X)
        self.V = V
        CV = np.tensordot(V, self.C, axes=(0, 0))  # (axes, n, 6)
        o, n = self.offsets, self.n
        self.T[:, o[2]:o[3]] = np.abs(CV).transpose(1, 0, 2).reshape(n, -1)
        self.T[:, o[4]:o[5]] = self._norms(CV).T
        self.slot_node = np.zeros(0, dtype=np.int64)  # kept columns are stale now
        self.node_slot[:] = -1

    def _keep(self, idx: np.ndarray) -> None:
        """Make the kept slots hold exactly the nodes ``idx`` (any order): a node that left
        is replaced by one from the end, new nodes appended (columns written once)."""
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
            slots = np.arange(m, m + new.size)
            self.Xs[slots // CHUNK, :, slots % CHUNK] = self.T[new]
            self.slot_node = np.concatenate([self.slot_node, new])
            self.node_slot[new] = slots

    def bounds_kept(self, stats: LoadStats, idx: np.ndarray, von_mises: bool
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(hi, lo, tv) (Pa) of nodes ``idx`` (distinct) over the block of ``stats``
        (:func:`load_stats`), their table rows kept in slots between calls."""
        build()
        self._keep(idx)
        m = self.slot_node.size
        hi, lo, tv = np.empty(m), np.empty(m), np.empty(m)
        _bound_slots(self.Xs, m, *stats, int(von_mises), self.offsets,
                     np.empty(ROWS * CHUNK), hi, lo, tv)
        at = self.node_slot[idx]
        return hi[at], lo[at], tv[at]


def damage_bound(hi: np.ndarray, lo: np.ndarray, tv: np.ndarray, mat: Material, method: str,
                 mean_stress: str, endurance: str | bool | None,
                 g: np.ndarray | None = None) -> np.ndarray:
    """Upper bound of each node's damage (residue closed, either mode) from its envelope
    [lo, hi] and variation tv (Pa) over the history, raised by the rounding margin; inf where
    the envelope is not finite. ``g`` (1/Pa): :func:`_per_range` of it, when known."""
    hi = np.asarray(hi, dtype=float)
    lo = np.asarray(lo, dtype=float)
    if g is None:
        g = _per_range(hi, lo, (mat, method, mean_stress, endurance))
    with np.errstate(invalid="ignore"):
        U = g * (tv + 0.5 * (hi - lo))
        ok = np.isfinite(hi) & np.isfinite(lo) & ~np.isnan(U)
        return np.where(ok, U * (1.0 + ROUNDING_MARGIN) + 1e-300, np.inf)


def _per_range(hi: np.ndarray, lo: np.ndarray, law: tuple) -> np.ndarray:
    """:func:`damage_per_range` where the envelope is finite, else inf."""
    ok = np.isfinite(hi) & np.isfinite(lo)
    g = np.full(hi.shape, np.inf)
    g[ok] = damage_per_range(hi[ok], lo[ok], *law)
    return g


DROP_MARGIN = 0.5
PROJECTED_MARGIN = 0.3
PROBE_SAMPLES = 2000
"""A candidate's bound rate is measured until it has seen this many samples."""


class Screening:
    """Which nodes must be computed exactly, block by block (the rule of :mod:`.worker`).

    Per node: the envelope [LO, HI] (:attr:`hi`, :attr:`lo`: exact while computed, else
    :class:`StressScreen`'s bounds), D0 the damage of the cycles closed when last computed,
    TVr the total variation of its rainflow residue then plus every block's bound since; the
    rest of the count is the counter run on the residue and the later samples, so
    D <= U = D0 + g(HI, LO) (TVr + (HI - LO)/2). The load blocks are kept (:attr:`history`):
    a node brought back is recomputed from where it was left out."""

    def __init__(self, coefficients: np.ndarray, equivalent: str, mat: Material, method: str,
                 mean_stress: str, endurance: str | bool | None, fraction: float) -> None:
        self.bounds = StressScreen(coefficients, equivalent)
        n = self.bounds.n
        self.fraction = float(fraction)
        self.law = (mat, method, mean_stress, endurance)
        self.hi = np.full(n, -np.inf)
        self.lo = np.full(n, np.inf)
        self.d0 = np.zeros(n)
        self.tv_r = np.zeros(n)
        self.threshold = 0.0
        self.total: int | None = None  # the history's samples, when known
        self.samples = 0
        self.history: list[np.ndarray] = []
        self._prev: np.ndarray | None = None
        self.caught_up = 0  # nodes brought back so far
        self.g = np.zeros(n)
        self.g_at = np.full((2, n), np.nan)  # the (hi, lo) g was computed at
        self.rate_tv = np.zeros(n)
        self.rate_n = np.zeros(n)
        """Per node: its bound's variation (Pa) and samples while bounded: rate_tv / rate_n."""
        self.probe = np.arange(n)
        """Computed nodes whose rate the next block measures (the candidates)."""

    def bound(self, idx: np.ndarray | None = None, tv: np.ndarray | None = None
              ) -> np.ndarray:
        """U of nodes ``idx`` (all when None), or with variation ``tv`` instead of theirs."""
        s = np.arange(self.hi.size) if idx is None else idx
        return self.d0[s] + damage_bound(self.hi[s], self.lo[s],
                                         self.tv_r[s] if tv is None else tv, *self.law,
                                         g=self._g(s))

    def _g(self, idx: np.ndarray) -> np.ndarray:
        """g of nodes ``idx``'s envelopes, recomputed only where an envelope changed since
        (most left-out nodes' envelopes stop growing early)."""
        stale = idx[(self.hi[idx] != self.g_at[0, idx]) | (self.lo[idx] != self.g_at[1, idx])]
        if stale.size:
            self.g[stale] = _per_range(self.hi[stale], self.lo[stale], self.law)
            self.g_at[:, stale] = self.hi[stale], self.lo[stale]
        return self.g[idx]

    def envelope(self, idx: np.ndarray, hi: np.ndarray, lo: np.ndarray) -> None:
        """A block's exact extremes of the equivalent stress of computed nodes ``idx``."""
        self.hi[idx] = np.maximum(self.hi[idx], hi)
        self.lo[idx] = np.minimum(self.lo[idx], lo)

    def settle(self, idx: np.ndarray, closed: np.ndarray, residue_tv: np.ndarray) -> None:
        """Computed nodes ``idx`` now: closed-cycle damage and their residue's variation."""
        self.d0[idx] = closed
        self.tv_r[idx] = residue_tv

    def add_block(self, F: np.ndarray, left_out: np.ndarray) -> None:
        """Keep the block; bound it for the nodes ``left_out`` and, for their rate, the
        candidates of :meth:`decide`."""
        F = np.asarray(F, dtype=float)
        Fe = F if self._prev is None else np.vstack([self._prev, F])
        self._prev = F[-1].copy()
        self.history.append(F.copy())
        self.samples += F.shape[0]
        probe, self.probe = self.probe, np.zeros(0, dtype=np.int64)
        if left_out.size + probe.size == 0:
            return
        hi, lo, tv = self.bounds.block(Fe, left_out, SUB_SAMPLES, probe)
        k = left_out.size
        for ids, part in ((probe, tv[k:]), (left_out, tv[:k])):  # their rates
            self.rate_tv[ids] += part
            self.rate_n[ids] += F.shape[0]
        self.envelope(left_out, hi[:k], lo[:k])
        self.tv_r[left_out] += tv[:k]

    def decide(self, active: np.ndarray, eq_max: np.ndarray, eq_min: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
        """(computed nodes to leave out, left-out nodes to bring back) after a block
        (:meth:`settle` done for the computed nodes ``active``).

        The threshold T = min(f D1, D10) (the largest and the tenth largest closed damage of
        the computed nodes) only grows. A node may stay out while U < T and its envelope lies
        strictly inside the computed nodes' extremes (docs/live_fatigue.md, "Screening"). A
        computed node is left out when U < DROP_MARGIN T and U projected to the end of the
        run with its measured rate (probed up to PROBE_SAMPLES) stays below PROJECTED_MARGIN
        T grown in proportion to the samples (efficiency only: a node brought back costs the
        replay of every block since)."""
        n = self.hi.size
        Da = self.d0[active]
        if Da.size >= TOP_NODES:
            d10 = float(np.partition(Da, Da.size - TOP_NODES)[Da.size - TOP_NODES])
            self.threshold = max(self.threshold, min(self.fraction * float(Da.max()), d10))
        T = self.threshold
        top, bottom = float(eq_max[active].max()), float(eq_min[active].min())
        is_active = np.zeros(n, dtype=bool)
        is_active[active] = True
        inside = (self.hi < top) & (self.lo > bottom)
        # U only where it decides (U >= D0: a computed node above the margin stays)
        need = np.nonzero(~is_active | (inside & (self.d0 < DROP_MARGIN * T)))[0]
        U = np.full(n, np.inf)
        U[need] = self.bound(need)
        back = np.nonzero(~is_active & ~(inside & (U < T)))[0]
        cand = np.nonzero(is_active & inside & (U < DROP_MARGIN * T))[0]
        left = (self.total - self.samples) if self.total else self.samples
        with np.errstate(invalid="ignore", divide="ignore"):
            rate = np.where(self.rate_n > 0, self.rate_tv / self.rate_n, np.nan)[cand]
        drop = cand[~np.isnan(rate)]
        if left > 0 and drop.size:
            u_end = self.bound(drop, self.tv_r[drop] + rate[~np.isnan(rate)] * left)
            t_end = T * (self.samples + left) / max(self.samples, 1)
            drop = drop[u_end < PROJECTED_MARGIN * t_end]
        probe = np.setdiff1d(cand, drop, assume_unique=True)
        self.probe = probe[self.rate_n[probe] < PROBE_SAMPLES]
        return drop, back
