"""The fatigue worker: loads -> nodal stresses -> equivalent stress -> rainflow -> Miner.

Batch (`analyse`) and live (`LiveFatigue`) run the same block-by-block engine: every block of
load samples is superposed into the six stress components of every node (Eq 6.1-6.6), reduced
to one signed equivalent stress per node, and fed to a streaming rainflow counter that keeps
each node's residue between blocks; closed cycles are turned into Miner damage at once. At the
end the residue is closed ("repeated" track, or ASTM half cycles). Because the counter is exact
across block boundaries, the live result equals the batch result on the same loads.

Life (Eq 2.7): D is the damage of one pass of the simulated history; life = 1/D passes
(repeats of the track) = L/D metres for a track of length L.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from cosim.errors import ScenarioError

from .config import BUILTIN_PART, FatigueConfig
from .influence import import_influence
from .lib import counting, screening, superposition, turning_eq
from .lib.counting import Cycles, StreamingRainflow
from .lib.damage import cycle_damage, per_range_unsupported
from .lib.equivalent_stress import equivalent_of
from .lib.influence_set import InfluenceSet, short_channel
from .lib.result import FatigueResult
from .lib.screening import Screening
from .lib.superposition import ROWS, components_buffer, node_major
from .lib.turning_eq import kept_equivalent, superpose_gather

TILE_ELEMS = 1 << 19
"""Stress components per node tile of the compiled path's signed von Mises (every sample:
6 x nodes x samples, 4 MB: 170 nodes of a 500-sample block); abs-max principal is fused
node by node (:func:`.turning_eq.superpose_gather`)."""
_SCRATCH = threading.local()  # per thread (a monolithic run's nodes are threads)


def _scratch(name: str, size: int) -> np.ndarray:
    """A flat float64 work array of at least ``size``, kept per thread and reused (fresh
    multi-MB arrays each tile cost their page faults: ~9 us per step)."""
    a = getattr(_SCRATCH, name, None)
    if a is None or a.size < size:
        a = np.empty(size)
        setattr(_SCRATCH, name, a)
    return a


_INFLUENCE_MEMO: dict[tuple, InfluenceSet] = {}


def warm_up() -> None:
    """Compile the engine's numba kernels now, or load them from numba's disk cache (once
    per process; cold ~3 s, cached ~1 s): :func:`load_influence` calls it, so the live node
    has them before it says ready, never in a run's step loop."""
    counting.build()
    superposition.build()
    turning_eq.build()
    screening.build()


def load_influence(cfg: FatigueConfig) -> InfluenceSet:
    """Influence coefficients for a config (built in, a part file ``*.toml`` meshed and solved
    by :mod:`nodes.fatigue.parts`, or imported), node set applied; the compiled kernels
    made ready too (:func:`warm_up`)."""
    warm_up()
    memo_key = (cfg.influence, str(cfg.influence_path), cfg.mapping, cfg.stress_scale,
                cfg.mesh_size_m, cfg.material, cfg.nodes)
    if memo_key in _INFLUENCE_MEMO:
        return _INFLUENCE_MEMO[memo_key]
    if cfg.influence == "builtin" or cfg.influence_path.suffix.lower() == ".toml":
        # a part file ("builtin": the CAD lower arm's): its shipped results when they
        # are this part's, else meshed and solved; mesh_size_m overrides its global size
        from .parts import load_part
        from .parts.results_file import part_results

        path = BUILTIN_PART if cfg.influence == "builtin" else cfg.influence_path
        inf = part_results(load_part(path), cfg.mesh_size_m)
    else:
        mapping = {c: {"file": f, "scale": s} for c, f, s in cfg.mapping}
        inf = import_influence(cfg.influence_path, mapping, cfg.stress_scale)
    if cfg.nodes == "surface":
        inf = inf.subset(inf.surface)
    _INFLUENCE_MEMO[memo_key] = inf
    return inf


@dataclass
class _Parked:
    """Nodes left out at the end of block ``block``: their counter and exact envelope then."""

    block: int
    nodes: np.ndarray
    rf: StreamingRainflow
    hi: np.ndarray
    lo: np.ndarray


class _Engine:
    """Block-by-block superposition, equivalent stress, streaming rainflow and Miner, over the
    nodes that screening keeps (all of them with ``screen=None``).

    Blocks are cut every ``block_samples`` samples from the first (batch and live alike: the
    same blocks, the same screening, the same bits). A node's damage is the sum of its cycles'
    damages in the order they close (``np.add.at``), so it does not depend on how the history
    was cut, nor on which other nodes were computed with it (:mod:`.superposition`).
    """

    def __init__(self, cfg: FatigueConfig, inf: InfluenceSet,
                 screen: float | None = None, total: int | None = None) -> None:
        self.cfg, self.inf = cfg, inf
        self.mat = cfg.material
        n = inf.n_nodes
        self.per_node = node_major(inf.coefficients)
        self.cols = np.arange(n)  # the nodes computed (their order in the counter)
        self.rf = StreamingRainflow(n)
        self.damage = np.zeros(n)
        self.ncyc = np.zeros(n)
        self.rmax = np.zeros(n)
        self.eq_max = np.full(n, -np.inf)
        self.eq_min = np.full(n, np.inf)
        self.n_samples = 0
        self.block = max(1, int(cfg.block_samples))
        why = None if not screen else per_range_unsupported(self.mat, cfg.method,
                                                          cfg.mean_stress_rule)
        self.screen_note = "off" if not screen else (why or "")
        self.scr: Screening | None = None
        self.parked: list[_Parked] = []
        if screen and why is None:
            self.scr = Screening(inf.coefficients, cfg.equivalent, self.mat, cfg.method,
                                 cfg.mean_stress_rule, cfg.endurance, float(screen))
            self.scr.total = total

    def push(self, F: np.ndarray) -> None:
        """F: (n_samples, n_cases) loads in case order (N), cut into blocks of
        ``block_samples`` from its first sample (the live node pushes one block at a time)."""
        for i in range(0, F.shape[0], self.block):
            self._block(F[i:i + self.block])
        self.n_samples += F.shape[0]

    def _block(self, F: np.ndarray) -> None:
        scr = self.scr
        if scr is not None:
            out = np.setdiff1d(np.arange(self.inf.n_nodes), self.cols, assume_unique=True)
            scr.add_block(F, out)
        self._exact(F, self.cols, self.rf)
        if scr is None:
            return
        scr.settle(self.cols, self.damage[self.cols], self.rf.residue_variation())
        drop, back = scr.decide(self.cols, self.eq_max, self.eq_min)
        if drop.size:
            self._park(drop)
        if back.size:
            self._catch_up(back)

    def _exact(self, F: np.ndarray, idx: np.ndarray, rf: StreamingRainflow) -> None:
        """Nodes ``idx`` (the counter ``rf``'s series) through block ``F``, exactly."""
        if idx.size == 0:
            return
        hi, lo, cyc = self._exact_compiled(F, idx, rf)
        self._add(cyc, idx, self.damage, self.ncyc, self.rmax)
        self.eq_max[idx] = np.maximum(self.eq_max[idx], hi)
        self.eq_min[idx] = np.minimum(self.eq_min[idx], lo)
        if self.scr is not None:
            self.scr.envelope(idx, hi, lo)

    def _exact_compiled(self, F: np.ndarray, idx: np.ndarray, rf: StreamingRainflow
                        ) -> tuple[np.ndarray, np.ndarray, Cycles]:
        """The block's extremes and cycles, node by node: the products (:mod:`.superposition`'s
        sum in case order) and the components of the samples that may be turning points
        gathered, fused per node (:func:`.turning_eq.superpose_gather`), then their exact
        equivalent stress and the counter fed those. Signed von Mises (every sample) goes by
        tiles of nodes. The tests swap in numpy oracles (``tests/fatigue/oracle_turning_eq.py``)."""
        n = F.shape[0]
        kind = self.cfg.equivalent
        whole = idx.size == self.per_node.shape[0] and bool(
            np.array_equal(idx, np.arange(idx.size)))
        coef = self.per_node if whole else self.per_node[idx]  # (a copy: 10 MB on the CAD arm)
        n_pad = -(-n // ROWS) * ROWS
        tile = max(1, TILE_ELEMS // (6 * n_pad))
        counts = np.empty(idx.size, dtype=np.int64)
        if kind == "abs_max_principal" and n > 2:
            cap = max(n, idx.size * n // 8)
            kept = _scratch("kept", 6 * cap)[:6 * cap].reshape(6, cap)
            pos = superpose_gather(F, coef, kept, counts)
            while pos < 0:  # more kept than room (rare, noise-like loads): larger, again
                cap = 2 * cap + idx.size * n // 4
                kept = np.empty((6, cap))
                pos = superpose_gather(F, coef, kept, counts)
            vals = equivalent_of(kept[:, :pos], kind)
        else:  # every sample (signed von Mises, or blocks of 1-2 samples)
            parts = []
            for j in range(0, idx.size, tile):
                k = min(tile, idx.size - j)
                buf, _ = components_buffer(F, coef[j:j + tile], _scratch("comp", 6 * k * n_pad))
                v, counts[j:j + k] = kept_equivalent(buf, n, kind)
                parts.append(v)
            vals = np.concatenate(parts)
        starts = np.cumsum(counts) - counts  # every count >= 1 (the block's ends)
        hi = np.maximum.reduceat(vals, starts)
        lo = np.minimum.reduceat(vals, starts)
        return hi, lo, rf.feed_packed(vals, counts, vals[starts + counts - 1])

    def _park(self, nodes: np.ndarray) -> None:
        """Leave computed nodes out: keep their exact state at the end of this block."""
        assert self.scr is not None
        out = np.isin(self.cols, nodes)
        pos = np.nonzero(out)[0]
        ids = self.cols[pos]
        self.parked.append(_Parked(len(self.scr.history) - 1, ids, self.rf.take(pos),
                                   self.scr.hi[ids].copy(), self.scr.lo[ids].copy()))
        keep = np.nonzero(~out)[0]
        self.rf, self.cols = self.rf.take(keep), self.cols[keep]

    def _catch_up(self, nodes: np.ndarray) -> None:
        """Bring left-out nodes back: from their state when they were left out, through
        the blocks since (kept loads), exactly as if they had never been left out. All of
        them together, one engine call per kept block: a group joins the replay at the
        block after the one it was left out at (a node's blocks in order, its cycles in the
        order they close: the same bits as node by node)."""
        assert self.scr is not None
        want = np.zeros(self.inf.n_nodes, dtype=bool)
        want[nodes] = True
        back: list[tuple[int, np.ndarray, StreamingRainflow]] = []
        still = []
        for g in self.parked:
            m = want[g.nodes]
            if not m.any():
                still.append(g)
                continue
            pos, rest = np.nonzero(m)[0], np.nonzero(~m)[0]
            ids = g.nodes[pos]
            self.scr.hi[ids], self.scr.lo[ids] = g.hi[pos], g.lo[pos]  # exact until then
            back.append((g.block, ids, g.rf.take(pos)))
            if rest.size:
                still.append(_Parked(g.block, g.nodes[rest], g.rf.take(rest), g.hi[rest],
                                     g.lo[rest]))
        self.parked = still
        back.sort(key=lambda b: b[0])
        hist = self.scr.history
        ids = np.zeros(0, dtype=np.int64)
        rf: StreamingRainflow | None = None
        i = 0
        for blk in range(back[0][0] + 1, len(hist) + 1):
            new = []
            while i < len(back) and back[i][0] < blk:
                new.append(back[i])
                i += 1
            if new:
                rf = StreamingRainflow.join(([rf] if rf is not None else [])
                                            + [b[2] for b in new])
                ids = np.concatenate([ids] + [b[1] for b in new])
            if blk < len(hist):
                assert rf is not None
                self._exact(hist[blk], ids, rf)
        assert rf is not None
        self.scr.caught_up += ids.size
        self.rf = StreamingRainflow.join([self.rf, rf])
        self.cols = np.concatenate([self.cols, ids])

    def _add(self, cyc: Cycles, idx: np.ndarray, damage: np.ndarray, ncyc: np.ndarray,
             rmax: np.ndarray) -> None:
        if len(cyc) == 0:
            return
        node = idx[cyc.series]
        np.add.at(damage, node, cycle_damage(cyc, self.mat, self.cfg.method,
                                             self.cfg.mean_stress_rule, self.cfg.endurance))
        np.add.at(ncyc, node, cyc.count)
        np.maximum.at(rmax, node, cyc.range)

    def result(self, track_length_m: float, duration_s: float,
               missing: list[str]) -> FatigueResult:
        damage, ncyc, rmax = self.damage.copy(), self.ncyc.copy(), self.rmax.copy()
        eq_max, eq_min = self.eq_max.copy(), self.eq_min.copy()
        self._add(self.rf.residue_cycles(self.cfg.residue), self.cols, damage, ncyc, rmax)
        screened = np.ones(damage.size, dtype=bool)
        screened[self.cols] = False
        meta: dict = {"fraction": None if self.scr is None else self.scr.fraction,
                      "screened_nodes": 0, "note": self.screen_note}
        if self.scr is not None and screened.any():
            # a left-out node: its bounds (damage <= U, envelope [LO, HI]), cycles unknown
            out = np.nonzero(screened)[0]
            damage[out] = self.scr.bound(out)
            eq_max[out], eq_min[out] = self.scr.hi[out], self.scr.lo[out]
            rmax[out] = self.scr.hi[out] - self.scr.lo[out]
            ncyc[out] = np.nan
            meta.update(screened_nodes=int(out.size), threshold=self.scr.threshold,
                        caught_up_nodes=self.scr.caught_up)
        return FatigueResult(
            damage=damage, node_ids=self.inf.node_ids, node_xyz=self.inf.node_xyz,
            eq_max=eq_max, eq_min=eq_min, eq_range_max=rmax,
            n_cycles=ncyc, track_length_m=float(track_length_m), duration_s=float(duration_s),
            n_samples=self.n_samples, config=self.cfg.as_dict(),
            influence_meta=self.inf.meta, missing_channels=missing,
            repeats_basis_m=self.cfg.repeats_basis_m, screened=screened, screening=meta,
        )


def _case_columns(case_names: Sequence[str], channels: Sequence[str]
                  ) -> tuple[list[int | None], list[str]]:
    """For each case, the index of its channel among ``channels`` (or None if absent)."""
    short = [short_channel(c) for c in channels]
    cols: list[int | None] = []
    missing: list[str] = []
    for name in case_names:
        if name in short:
            cols.append(short.index(name))
        else:
            cols.append(None)
            missing.append(f"plant/arm/{name}")
    if all(c is None for c in cols):
        raise ScenarioError("fatigue.influence", sorted(channels)[:8],
                            "load channels for the cases " + ", ".join(
                                f"plant/arm/{n}" for n in case_names))
    return cols, missing


def _matrix(cols: list, data: Sequence[np.ndarray], n: int) -> np.ndarray:
    F = np.zeros((n, len(cols)))
    for j, c in enumerate(cols):
        if c is not None:
            F[:, j] = data[c]
    return F


def case_matrix(cases: Sequence[str], loads: Mapping[str, np.ndarray]) -> np.ndarray:
    """(n, cases) loads in case order from channel -> (n,) values (N, N m; a case without a
    channel: zero)."""
    names = list(loads)
    data = [np.asarray(loads[k], dtype=float) for k in names]
    return _matrix(_case_columns(cases, names)[0], data, data[0].size if data else 0)


def analyse(t: np.ndarray, loads: Mapping[str, np.ndarray], cfg: FatigueConfig,
            track_length_m: float, screen: float | None = None) -> FatigueResult:
    """Fatigue of the arm for one pass of recorded loads: :class:`LiveFatigue` fed the whole
    history. ``t`` (n,) sample times (s); ``loads``: channel -> (n,) load history in N or N m
    (``plant/arm/<point>_<axis>`` or short ``<point>_<axis>``; channels without a load case
    are ignored, cases without a channel get zero load, listed in ``missing_channels``);
    ``track_length_m``: the road the history covers (m), for life in km; ``screen``: the
    screening fraction f (:mod:`.screening`; None: every node computed): the lives of the
    nodes that can reach f of the largest damage, the critical node, the ten most damaged
    nodes and the extremes of the equivalent stress are the unscreened ones bit for bit; a
    node left out reports upper bounds."""
    t = np.asarray(t, dtype=float)
    for k, a in loads.items():
        if np.shape(a) != t.shape:
            raise ScenarioError(f"loads.{k}", np.shape(a), f"an array of shape {t.shape} like t")
    lf = LiveFatigue(cfg, list(loads), track_length_m, screen, t.size)
    lf.update(t, loads)
    return lf.result()


class LiveFatigue:
    """Damage updated block by block while a run streams loads in: :meth:`update` takes consecutive
    blocks (``t_block`` (n,), ``loads_block`` (n, len(channels)) or channel -> (n,); ``channels``:
    the load columns' names), :meth:`result` may be called at any time. At the end it equals
    :func:`analyse` on the concatenated loads, bit for bit when the blocks are those analyse cuts
    (``block_samples`` from the first). ``screen``: the screening fraction (None: every node
    computed); ``total_samples``: the history's length when known (screening leaves nodes out
    sooner)."""

    def __init__(self, cfg: FatigueConfig, channels: Sequence[str],
                 track_length_m: float | None = None, screen: float | None = None,
                 total_samples: int | None = None) -> None:
        self.cfg = cfg
        self.channels = list(channels)
        self.inf = load_influence(cfg)
        self._cols, self._missing = _case_columns(self.inf.case_names, self.channels)
        self._eng = _Engine(cfg, self.inf, screen, total_samples)
        self.track_length_m = track_length_m if track_length_m is not None \
            else cfg.track_length_m
        self._t0: float | None = None
        self._t_last: float | None = None
        self._dt: float = 0.0

    def update(self, t_block: np.ndarray, loads_block) -> None:
        t_block = np.asarray(t_block, dtype=float).ravel()
        if isinstance(loads_block, Mapping):
            data = [np.asarray(loads_block[c], dtype=float) for c in self.channels]
        else:
            arr = np.asarray(loads_block, dtype=float).reshape(t_block.size, -1)
            if arr.shape[1] != len(self.channels):
                raise ValueError(f"loads_block has {arr.shape[1]} columns, expected "
                                 f"{len(self.channels)}")
            data = [arr[:, j] for j in range(arr.shape[1])]
        if t_block.size == 0:
            return
        if self._t0 is None:
            self._t0 = float(t_block[0])
        if t_block.size > 1:
            self._dt = float(t_block[1] - t_block[0])
        elif self._t_last is not None:
            self._dt = float(t_block[0] - self._t_last)
        self._t_last = float(t_block[-1])
        self._eng.push(_matrix(self._cols, data, t_block.size))

    def result(self, track_length_m: float | None = None) -> FatigueResult:
        L = track_length_m if track_length_m is not None else self.track_length_m
        # _t0 and _t_last are set together, by the first block
        duration = 0.0 if self._t0 is None or self._t_last is None \
            else self._t_last - self._t0 + self._dt
        return self._eng.result(float("nan") if L is None else L, duration,
                                list(self._missing))
