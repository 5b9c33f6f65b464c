"""The equivalent stress only where rainflow needs it: the same cycles, bit for bit.

The numpy oracle (``oracle_turning_eq.turning_equivalent``) against the whole block, and
the product's compiled path (:func:`nodes.fatigue.lib.turning_eq.kept_equivalent`) against both:
the same cycles (the kept samples differ: its bracket is another one), bit for bit."""

from __future__ import annotations

import numpy as np
import rainflow
from hypothesis import given, settings
from hypothesis import strategies as st

from nodes.fatigue.lib.counting import Cycles, StreamingRainflow
from nodes.fatigue.lib.equivalent_stress import equivalent_of
from nodes.fatigue.lib.superposition import superpose_components
from nodes.fatigue.lib.turning_eq import kept_equivalent

from .oracle_turning_eq import feed_lock_step, feed_points, turning_equivalent, turning_points


def _both(comp_blocks: list[np.ndarray], kind: str = "abs_max_principal"
          ) -> tuple[list[Cycles], list[Cycles], StreamingRainflow, StreamingRainflow]:
    k = comp_blocks[0].shape[2]
    ref, new, cmp = StreamingRainflow(k), StreamingRainflow(k), StreamingRainflow(k)
    out_r, out_n = [], []
    for comp in comp_blocks:
        eq = equivalent_of(comp, kind)
        out_r.append(feed_lock_step(ref, eq))
        rows, last, hi, lo = turning_equivalent(comp, kind, new.last)
        assert np.array_equal(last, eq[-1])
        assert np.array_equal(hi, eq.max(axis=0)) and np.array_equal(lo, eq.min(axis=0))
        kept = turning_points(eq, None if len(out_n) == 0 else new.last)
        assert rows.shape[0] >= 1 and kept.shape[1] == rows.shape[1]
        out_n.append(feed_points(new, rows, last))
        n = comp.shape[1]  # the product's compiled path: exact values, the same cycles
        vals, counts = kept_equivalent(np.ascontiguousarray(comp.transpose(0, 2, 1)), n, kind)
        at = np.cumsum(counts) - counts
        assert np.array_equal(vals[at], eq[0]) and np.array_equal(vals[at + counts - 1], last)
        assert _same(out_r[-1], cmp.feed_packed(vals, counts, last))
    for mode in ("half_cycles", "repeated"):
        assert _same(ref.residue_cycles(mode), cmp.residue_cycles(mode))
    return out_r, out_n, ref, new


def _same(a: Cycles, b: Cycles) -> bool:
    """The same cycles of every node in the same order (the order across nodes is free:
    a node's damage sums its own cycles in order, ``np.add.at``)."""
    oa, ob = np.argsort(a.series, kind="stable"), np.argsort(b.series, kind="stable")
    return all(np.array_equal(getattr(a, f)[oa], getattr(b, f)[ob])
               for f in ("series", "s1", "s2", "count"))


def _blocks(rng: np.random.Generator, n: int, k: int, smooth: bool, hydro: float
            ) -> list[np.ndarray]:
    coef = rng.normal(size=(k, 15, 6)) * 1e4
    coef[:, :, :3] += hydro * rng.normal(size=(k, 15, 1)) * 1e4  # near-hydrostatic nodes
    t = np.arange(n)[:, None]
    if smooth:  # sampled oscillations, like the run's loads
        F = np.sin(2 * np.pi * t * rng.uniform(0.002, 0.05, 15) + rng.uniform(0, 6, 15)) * 1e3
    else:
        F = rng.normal(size=(n, 15)) * 1e3
    comp = superpose_components(F, coef)
    cuts = [0, *sorted(rng.choice(np.arange(1, n), 3, replace=False).tolist()), n]
    return [comp[:, a:b] for a, b in zip(cuts[:-1], cuts[1:], strict=True) if b > a]


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), smooth=st.booleans(),
       hydro=st.sampled_from([0.0, 30.0]))
def test_same_cycles_extremes_and_residue_as_whole_block(seed: int, smooth: bool,
                                                         hydro: float) -> None:
    rng = np.random.default_rng(seed)
    blocks = _blocks(rng, 300, 40, smooth, hydro)
    out_r, out_n, ref, new = _both(blocks)
    assert all(_same(a, b) for a, b in zip(out_r, out_n, strict=True))
    for mode in ("half_cycles", "repeated"):
        assert _same(ref.residue_cycles(mode), new.residue_cycles(mode))


def test_degenerate_and_switching_tensors() -> None:
    """Equal principal stresses (r = +-1) and |σ1| = |σ3| (the sign choice) exactly."""
    n, k = 200, 6
    t = np.linspace(0, 4 * np.pi, n)
    comp = np.zeros((6, n, k))
    comp[0, :, 0] = comp[1, :, 0] = comp[2, :, 0] = 1e8 * np.sin(t)  # hydrostatic
    comp[0, :, 1] = 1e8 * np.sin(t)  # uniaxial: two zero principal stresses
    comp[0, :, 2], comp[1, :, 2] = 1e8 * np.sin(t), -1e8 * np.sin(t)  # |σ1| = |σ3|
    comp[3, :, 3] = 1e8 * np.cos(t)  # pure shear: |σ1| = |σ3|
    comp[0, :, 4] = 1e8 * np.sin(t) + 1e3 * np.cos(37 * t)
    comp[0, :, 5] = comp[1, :, 5] = 2e8
    comp[2, :, 5] = 2e8 + 1e2 * np.sin(t)
    out_r, out_n, ref, new = _both([comp[:, :90], comp[:, 90:]])
    assert all(_same(a, b) for a, b in zip(out_r, out_n, strict=True))
    assert _same(ref.residue_cycles("half_cycles"), new.residue_cycles("half_cycles"))


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_cycle_count_equals_rainflow_package(seed: int) -> None:
    rng = np.random.default_rng(seed)
    blocks = _blocks(rng, 250, 3, bool(seed % 2), 0.0)
    _, out_n, _, new = _both(blocks)
    cyc = Cycles.concat([*out_n, new.residue_cycles("half_cycles")])
    eq = np.concatenate([equivalent_of(b, "abs_max_principal") for b in blocks])
    for i in range(3):
        ours: dict[float, float] = {}
        sel = cyc.series == i
        for r, c in zip(cyc.range[sel].tolist(), cyc.count[sel].tolist(), strict=True):
            ours[r] = ours.get(r, 0.0) + c
        theirs: dict[float, float] = {}
        for r, c in rainflow.count_cycles(eq[:, i]):
            theirs[r] = theirs.get(r, 0.0) + c
        assert ours == theirs


def test_signed_von_mises_falls_back_to_the_whole_block() -> None:
    rng = np.random.default_rng(1)
    out_r, out_n, _, _ = _both(_blocks(rng, 120, 10, True, 0.0), "signed_von_mises")
    assert all(_same(a, b) for a, b in zip(out_r, out_n, strict=True))
