"""Screening: an upper bound of each node's Miner damage from the loads' block statistics.

Computing a node's damage exactly costs its stresses at every sample (superposition, the
equivalent stress, rainflow). This module bounds it from what a block of load samples gives
in a few matrix-vector products for all nodes at once, so that a node whose bound stays below
a stated fraction of the damage already reached need not be computed (:mod:`.worker`).

**The bound** (one node, equivalent-stress history e_k, k = 0..N-1, Pa). With the node's
influence coefficients A_c (6 components per load case c) the stress is σ(t) = Σ_c A_c F_c(t).
Per block of loads (the previous block's last sample included):

1. *Envelope* [lo, hi] of e over the block. With F_mid the middle and h_c the half range of
   each load over the block, σ(t) = σ_mid + E(t), |E_ij| <= R_ij = Σ_c |A_c,ij| h_c; the
   spectral norm ||E|| <= λmax(R) =: ρ (a non-negative matrix bounds |E|'s spectral radius,
   Perron-Frobenius). Weyl's inequality puts each principal stress within ρ of σ_mid's.
   *abs_max_principal*: e = σ1 where σ1 + σ3 >= 0 (then σ1 >= 0), else σ3 (< 0); σ1 + σ3 moves
   by at most 2ρ, which tells which branches the block can take. *signed_von_mises*: the von
   Mises stress is a seminorm (|vm(a) - vm(b)| <= vm(a - b)), vm(E) <= sqrt(R·|Q|·R) with Q its
   quadratic form; the hydrostatic stress, linear in the loads, has the exact interval
   tr(σ_mid)/3 ± Σ_c |tr A_c|/3 h_c.
2. *Total variation* TV = Σ_k |e_k - e_(k-1)|. On a step that keeps the branch,
   |Δe| <= N(Δσ) with N the Frobenius norm (>= the spectral norm, 1-Lipschitz for σ1, σ3) or
   vm. A step that changes the branch jumps by at most 2 N(Δσ) + J: J = 2 max min(|σ1|, |σ3|)
   (the jump's ends are both near the switching surface |σ1| = |σ3|), or 2 max vm for the
   signed von Mises. Σ_k N(Δσ_k) over the block is at most the smaller of
   Σ_m N(A v_m) Σ_k |z_mk| (the loads' increments in the principal axes v_m of their scatter
   matrix S = Σ_k ΔF_k ΔF_kᵀ, z = Vᵀ ΔF) and sqrt(n Σ_m λ_m N(A v_m)²) (Cauchy-Schwarz,
   Σ_k N(Δσ_k)² = tr(G S) for N² = ΔFᵀ G ΔF). A block where the branch can change counts
   every step as a possible change.
3. *Damage.* The rainflow count removes pairs b, c from a, b, c, d with |b - c| <= |a - b|,
   |c - d|: the history's total variation drops by exactly 2|b - c|. So the full cycles' ranges
   sum to (TV - TV(residue)) / 2; half cycles of the residue sum to TV(residue) / 2, and the
   repeated residue closes cycles whose 2Δ sum to at most 2 TV(residue) + |r_m - r_1|:
   Σ count·Δ <= TV + (HI - LO) / 2 in both residue modes (HI, LO: the envelope over all
   blocks). A cycle's damage d(σa, σm) (stress-life) grows with σm and d / σa grows with σa
   (Basquin slopes k >= 1, Haibach 2k - 1, SWT needs k >= 2); a cycle of amplitude a in
   [LO, HI] has σm <= HI - a, so on a grid a_j = j A / K (A = (HI - LO) / 2) every cycle has
   d <= Δ · max_j d(a_(j+1), HI - a_j) / (2 a_(j+1)) =: Δ · g, and D <= g (TV + (HI - LO)/2).

:meth:`StressScreen.block` computes steps 1-2 in numba (:mod:`.screen_bound`, the compiled
kernels and their node tables; without the Cauchy-Schwarz sum: ~1.8 ns per node-sample for
25-sample sub-blocks against 11-14 for the exact path); this module holds step 3 and the
rule of which nodes are computed (:class:`Screening`). The bound is rigorous for every
history (the tests check it against exact counts); it is not tight (it takes every cycle as
large as the largest one can be), which only costs how many nodes are screened out, never a
wrong result. Rounding: the bound is raised by :data:`ROUNDING_MARGIN` (relative), far above
the float error of its few sums.
"""

from __future__ import annotations

import numpy as np

from .damage import cycle_reversals, sn_curve
from .life_models import SNCurve
from .material import Material
from .screen_bound import NodeTables, load_stats

SCREEN_FRACTION = 1e-2
"""Suggested screening fraction f (screening is off unless asked for: ``screen=`` of
:func:`.worker.analyse` / :class:`.worker.LiveFatigue`; docs/live_fatigue.md): a node
is left out while its damage bound is below f times the largest damage reached (and below
the tenth largest, and its stress envelope inside the computed nodes' extremes); see
:mod:`.worker` ``_Engine``."""
TOP_NODES = 10
"""The reported most damaged nodes (``summary.json`` ``top_nodes``): never screened out."""
ROUNDING_MARGIN = 1e-9
SUB_SAMPLES = 25
"""Samples per sub-block of the envelope (:class:`StressScreen`)."""
GRID = 8
"""Amplitude intervals of the damage-per-range bound g."""

_FROB = np.array([1.0, 1.0, 1.0, 2.0, 2.0, 2.0])
"""Frobenius norm² of a symmetric tensor from its 6 components (σx σy σz τxy τyz τzx)."""
_VM = np.array([[1.0, -0.5, -0.5, 0, 0, 0], [-0.5, 1.0, -0.5, 0, 0, 0],
                [-0.5, -0.5, 1.0, 0, 0, 0], [0, 0, 0, 3.0, 0, 0], [0, 0, 0, 0, 3.0, 0],
                [0, 0, 0, 0, 0, 3.0]])
"""vm² = sᵀ Q s (von Mises, 6 components)."""


def unsupported(mat: Material, method: str, mean_stress: str) -> str | None:
    """Why the damage bound does not hold for these settings (None: it does): stress-life,
    a mean-stress correction linear in σa at a given σm (or SWT), S-N slopes k >= 1 (2 for
    SWT) on every segment, so that a cycle's damage per unit of range grows with its range."""
    if method != "stress_life":
        return f"method {method!r} (the bound is proven for stress_life)"
    if mean_stress not in ("none", "goodman", "gerber", "morrow", "swt"):
        return f"mean_stress {mean_stress!r} (the bound is proven for none, goodman, " \
               "gerber, morrow, swt)"
    curve = sn_curve(mat)
    if isinstance(curve, SNCurve):
        slopes = [curve.k]
        if curve.lcf_Su is not None:
            b_lcf = np.log(curve.lcf_stress / curve.lcf_Su) / np.log(curve.lcf_reversals / 2.0)
            slopes.append(-1.0 / b_lcf)
    elif hasattr(curve, "n_cycles") and hasattr(curve, "s_amp"):  # a tabulated curve
        logn, logs = np.log(np.asarray(curve.n_cycles)), np.log(np.asarray(curve.s_amp))
        slopes = list(-np.diff(logn) / np.diff(logs))
        tail = getattr(curve, "tail_b", None)
        if tail is not None and tail < 0.0:
            slopes.append(-1.0 / tail)
    else:
        return f"an S-N curve of type {type(curve).__name__}"
    need = 2.0 if mean_stress == "swt" else 1.0
    if min(slopes) < need:
        return f"an S-N slope k = {min(slopes):.3g} < {need:g} (damage per range must grow)"
    return None


def damage_per_range(hi: np.ndarray, lo: np.ndarray, mat: Material, method: str,
                     mean_stress: str, endurance: str | bool | None) -> np.ndarray:
    """g (1/Pa): every cycle with both extremes in [lo, hi] (Pa) has damage <= g · its range."""
    hi = np.asarray(hi, dtype=float)
    lo = np.asarray(lo, dtype=float)
    A = np.maximum(0.5 * (hi - lo), 0.0)
    j = np.arange(GRID, dtype=float)
    a0 = A[:, None] * (j / GRID)
    a1 = A[:, None] * ((j + 1.0) / GRID)
    m = hi[:, None] - a0
    finite = np.isfinite(a1) & np.isfinite(m)
    a1f, mf = np.where(finite, a1, 0.0), np.where(finite, m, 0.0)
    rev = cycle_reversals(mf + a1f, mf - a1f, mat, method, mean_stress, endurance)
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.where(a1f > 0.0, (2.0 / rev) / (2.0 * a1f), 0.0)
    g = np.where(finite, g, np.inf)
    return g.max(axis=1) if g.size else np.zeros(hi.shape)


class StressScreen:
    """Bounds of the equivalent stress of any set of nodes over a block of loads, from the
    loads alone (module docstring): the envelope [lo, hi] and the total variation TV. Each
    block is cut into sub-blocks of ``sub_samples``: the smaller a sub-block's load ranges,
    the tighter its envelope, and only sub-blocks where the branch can change count their
    steps as jumps; the cost grows with the number of sub-blocks."""

    def __init__(self, coefficients: np.ndarray, equivalent: str) -> None:
        C = np.asarray(coefficients, dtype=float)
        self.n_cases, self.n, _ = C.shape
        self.C = C  # (cases, n, 6)
        self.abs_tr3 = np.abs(C[:, :, 0] + C[:, :, 1] + C[:, :, 2]) / 3.0  # (cases, n)
        self.kind = equivalent
        self.Q = np.diag(_FROB) if equivalent == "abs_max_principal" else _VM
        self.NA = self._norms(C)  # N(A_c) per case and node
        self.V: np.ndarray | None = None
        self.CV = self.NAV = np.zeros(0)
        self._tables = NodeTables(C, self.NA, self.abs_tr3)

    def block(self, Fe: np.ndarray, idx: np.ndarray, sub_samples: int,
              probe: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(hi, lo, tv) of nodes ``idx`` over the samples of ``Fe`` (n_e, cases): the block's
        loads with the previous block's last sample first (its increment counts; the
        envelope covers it too; TV covers the n_e - 1 increments). By the numba kernel of
        :mod:`.screen_bound` (per node ~22 floating-point operations per sample), the nodes
        ``idx`` kept in its slots between calls (the left-out set); ``probe``: more nodes
        (gathered for this call), their results after idx's."""
        if self.V is None:
            self.set_axes(Fe)
        assert self.V is not None
        stats = load_stats(np.asarray(Fe, dtype=float), self.V, sub_samples)
        vm = self.kind != "abs_max_principal"
        out = self._tables.bounds_kept(stats, idx, vm)
        if probe is None or probe.size == 0:
            return out
        more = self._tables.bounds(stats, probe, vm)
        return (np.concatenate([out[0], more[0]]), np.concatenate([out[1], more[1]]),
                np.concatenate([out[2], more[2]]))

    def _norms(self, C: np.ndarray) -> np.ndarray:
        """N of each case's stress tensor per node: (cases, n)."""
        return np.sqrt(np.maximum(((C @ self.Q) * C).sum(axis=2), 0.0))

    def set_axes(self, F: np.ndarray) -> None:
        """Principal axes of a block of loads (the first): correlated loads (joint loads in
        equilibrium) bound much tighter along them than channel by channel."""
        X = np.asarray(F, dtype=float)
        X = X - X.mean(axis=0)
        _, V = np.linalg.eigh(X.T @ X)
        self.V = V
        self.CV = np.tensordot(V, self.C, axes=(0, 0))  # (axes, n, 6)
        self.NAV = self._norms(self.CV)
        self._tables.set_axes(self.CV, self.NAV)


def damage_bound(hi: np.ndarray, lo: np.ndarray, tv: np.ndarray, mat: Material, method: str,
                 mean_stress: str, endurance: str | bool | None,
                 g: np.ndarray | None = None) -> np.ndarray:
    """Upper bound of each node's damage (residue closed, either mode) from its envelope
    [lo, hi] and total variation tv over the history: g (TV + (HI - LO)/2), raised by the
    rounding margin; inf where the envelope is not finite. ``g``: :func:`damage_per_range`
    of this envelope when already known (1/Pa, per node)."""
    hi = np.asarray(hi, dtype=float)
    lo = np.asarray(lo, dtype=float)
    out = np.full(hi.shape, np.inf)
    seen = np.isfinite(hi) & np.isfinite(lo)
    if not seen.any():
        return out
    g = damage_per_range(hi[seen], lo[seen], mat, method, mean_stress, endurance) \
        if g is None else np.asarray(g)[seen]
    with np.errstate(invalid="ignore"):
        U = g * (tv[seen] + 0.5 * (hi[seen] - lo[seen]))
    out[seen] = np.where(np.isnan(U), np.inf, U) * (1.0 + ROUNDING_MARGIN) + 1e-300
    return out


DROP_MARGIN = 0.5
"""A computed node is left out only when its bound is below this share of the threshold: its
bound grows faster once it is no longer computed exactly (hysteresis: fewer catch-ups)."""
PROJECTED_MARGIN = 0.3
"""A candidate to leave out is left out only when its bound projected to the end of the run
(its bound's variation per sample, :attr:`Screening.rate`, times the samples left) stays
below this share of the threshold projected alike (grown in proportion to the samples)."""
PROBE_SAMPLES = 2000
"""A candidate computed node's bound is measured (:attr:`Screening.rate`) until it has
seen this many samples; then its rate is taken as known."""


class Screening:
    """Which nodes must be computed exactly, block by block (the rule of :mod:`.worker`).

    Per node it keeps the envelope [LO, HI] of the equivalent stress over the history (exact
    for the blocks in which the node was computed, bounds of :class:`StressScreen` for the
    others), the damage D0 of the cycles closed when it was last computed (exact), and TVr:
    the total variation of its rainflow residue then plus the bounds of the variation of
    every block since. The rest of the count is the counter run on the residue and the
    later samples, so (module docstring, step 3, on that sequence)

        D <= U = D0 + g(HI, LO) (TVr + (HI - LO)/2)

    bounds the node's damage so far, residue closed, however each block was taken. The load
    blocks are kept (:attr:`history`) so that a node brought back is recomputed from where
    it was left out (its exact state then is kept by the engine).
    """

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
        self.total: int | None = None
        """Samples the whole history will have, when known (batch, or the run's steps)."""
        self.samples = 0
        self.history: list[np.ndarray] = []
        self._prev: np.ndarray | None = None
        self.caught_up = 0
        self.g = np.zeros(n)
        self.g_at = np.full((2, n), np.nan)
        """The envelopes (hi, lo) at which :attr:`g` was computed (NaN: not yet)."""
        self.rate_tv = np.zeros(n)
        self.rate_n = np.zeros(n)
        self.probe = np.arange(n)
        """Computed nodes whose :attr:`rate` the next block measures (the candidates)."""
        """Nodes brought back so far (each recomputed from where it was left out)."""

    def bound(self, idx: np.ndarray | None = None, tv: np.ndarray | None = None
              ) -> np.ndarray:
        """U of nodes ``idx`` (all when None), or with variation ``tv`` instead of theirs;
        g of their envelope from :meth:`_g`."""
        s = np.arange(self.hi.size) if idx is None else idx
        return self.d0[s] + damage_bound(self.hi[s], self.lo[s],
                                         self.tv_r[s] if tv is None else tv, *self.law,
                                         g=self._g(s))

    def _g(self, idx: np.ndarray) -> np.ndarray:
        """:func:`damage_per_range` of nodes ``idx``'s envelopes, recomputed only where an
        envelope changed since (most left-out nodes' envelopes stop growing early)."""
        stale = idx[(self.hi[idx] != self.g_at[0, idx]) | (self.lo[idx] != self.g_at[1, idx])]
        if stale.size:
            h, lo = self.hi[stale], self.lo[stale]
            ok = np.isfinite(h) & np.isfinite(lo)
            g = np.full(stale.size, np.inf)
            g[ok] = damage_per_range(h[ok], lo[ok], *self.law)
            self.g[stale] = g
            self.g_at[:, stale] = h, lo
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
        """Keep the block; bound it (:meth:`StressScreen.block`, sub-blocks of
        :data:`SUB_SAMPLES`) for the nodes ``left_out``, and for the computed nodes to probe
        (:meth:`decide`) their bound's variation per sample over this block (:attr:`rate`)."""
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
        self._rate(probe, tv[k:], F.shape[0])
        hi, lo, tv = hi[:k], lo[:k], tv[:k]
        self._rate(left_out, tv, F.shape[0])
        self.envelope(left_out, hi, lo)
        self.tv_r[left_out] += tv

    def _rate(self, idx: np.ndarray, tv: np.ndarray, samples: int) -> None:
        """Add a block's variation bounds ``tv`` (Pa) of nodes ``idx`` to their rate."""
        self.rate_tv[idx] += tv
        self.rate_n[idx] += samples

    @property
    def rate(self) -> np.ndarray:
        """Per node: its bound's variation per sample (Pa) over the blocks it was bounded
        in (left out, or a candidate to be); NaN: never bounded yet."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.rate_n > 0, self.rate_tv / self.rate_n, np.nan)

    def decide(self, active: np.ndarray, eq_max: np.ndarray, eq_min: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
        """(computed nodes to leave out, left-out nodes to bring back) after a block
        (:meth:`settle` done for the computed nodes ``active``).

        The threshold T = min(f D1, D10), D1 and D10 the largest and the tenth largest
        closed-cycle damage of the computed nodes (lower bounds of the final ones), only
        grows. A node may stay out while U < T and its envelope lies strictly inside the
        computed nodes' extremes of the equivalent stress: then it is not the critical node,
        not among the ten most damaged and below f of the largest damage, and the reported
        extremes are computed ones. A computed node is left out when it qualifies with
        U < DROP_MARGIN T (hysteresis: its bound grows faster once it is left out) and,
        projected to the end of the run with its measured :attr:`rate` (probed while it
        is a candidate), stays below PROJECTED_MARGIN times T grown in proportion to the
        samples: a node brought back costs the replay of every block since (efficiency
        only; what keeps a node out is the first rule)."""
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
        # projected to the end of the run: left out only if it would likely stay out
        # (a node brought back costs its replay: efficiency, never correctness)
        left = (self.total - self.samples) if self.total else self.samples
        rate = self.rate[cand]
        drop = cand[~np.isnan(rate)]
        if left > 0 and drop.size:
            u_end = self.bound(drop, self.tv_r[drop] + rate[~np.isnan(rate)] * left)
            t_end = T * (self.samples + left) / max(self.samples, 1)
            drop = drop[u_end < PROJECTED_MARGIN * t_end]
        probe = np.setdiff1d(cand, drop, assume_unique=True)
        self.probe = probe[self.rate_n[probe] < PROBE_SAMPLES]
        return drop, back
