"""The compiled fatigue engine (#28): a proven bracket, the same cycles, the same bits.

numba is a dependency: without it this module fails at its import (never skipped). The
compiled engine is the product's one path; the numpy oracles it is compared with, bit for
bit, are in ``oracle_turning_eq.py``.
"""

from __future__ import annotations

import numba  # noqa: F401  (required: the test fails clearly where it is missing)
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cosim import plaindata
from nodes.fatigue import worker
from nodes.fatigue.config import FatigueConfig
from nodes.fatigue.lib import counting, screening, turning_eq
from nodes.fatigue.lib.counting import StreamingRainflow
from nodes.fatigue.lib.equivalent_stress import equivalent_of
from nodes.fatigue.lib.superposition import components_buffer, superpose_components
from nodes.fatigue.synthetic import pave_like_loads
from tests.conftest import COARSE_ARM

from .oracle_turning_eq import (
    exact_block,
    exact_numpy,
    lock_step,
    repeated_lock_step,
    turning_points,
)

COARSE = {"influence": str(COARSE_ARM)}  # a cheap arm, results shipped
FIELDS = ("damage", "eq_max", "eq_min", "eq_range_max", "n_cycles")


@pytest.fixture(autouse=True)
def _cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("SUSCOSIM_CACHE", str(tmp_path_factory.getbasetemp() / "cache"))


def _brackets(comp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(k, n) brackets of the kernel for components (6, k, n)."""
    _, k, n = comp.shape
    turning_eq.build()
    lo, hi = np.empty((k, n)), np.empty((k, n))
    out, counts = np.empty((6, n)), np.empty(1, dtype=np.int64)
    w = np.empty((6, n))
    for i in range(k):
        one = np.ascontiguousarray(comp[:, i:i + 1, :])
        turning_eq._keep_gather(one, n, out, 0, counts, lo[i], hi[i], w)
    return lo, hi


def _exact(comp: np.ndarray) -> np.ndarray:
    """(k, n) the exact path's abs-max principal stress of components (6, k, n)."""
    return equivalent_of(comp, "abs_max_principal")


def _hard_tensors(n: int = 400) -> np.ndarray:
    """(6, k, n): hydrostatic, uniaxial +-, |σ1| = |σ3|, pure shear, near-degenerate,
    tiny and huge scales, a deviator tiny against the mean stress, zeros, NaN and inf."""
    t = np.linspace(0.0, 6 * np.pi, n)
    s = np.sin(t)
    cols = []

    def add(**kw):
        c = np.zeros((6, n))
        for j, name in enumerate(("sx", "sy", "sz", "txy", "tyz", "tzx")):
            if name in kw:
                c[j] = kw[name]
        cols.append(c)

    add(sx=1e8 * s, sy=1e8 * s, sz=1e8 * s)  # hydrostatic: p = 0
    add(sx=1e8 * s)  # uniaxial: r = +-1, a double root
    add(sx=-1e8 * np.abs(s))  # uniaxial compression only
    add(sx=1e8 * s, sy=-1e8 * s)  # |σ1| = |σ3|
    add(txy=1e8 * np.cos(t))  # pure shear
    add(sx=1e8 * s + 1e3 * np.cos(37 * t))
    add(sx=2e8 + 0 * s, sy=2e8 + 0 * s, sz=2e8 + 1e2 * s)  # deviator 1e-6 of the mean
    add(sx=1e8 * s, sy=1e8 * s + 1e-3 * np.cos(t), txy=1e-4 * s)  # equal σ1, σ2
    add(sx=1e-200 * s, txy=3e-201 * np.cos(t))  # tiny
    add(sx=1e-310 * s)  # subnormal
    add(sx=1e80 * s, sy=-3e79 * s)  # large
    add(sx=1e150 * s)  # det overflows: the exact value is NaN
    add()  # zeros
    nan = np.where(np.arange(n) % 17 == 3, np.nan, 1e8 * s)
    add(sx=nan, txy=1e7 * s)
    inf = np.where(np.arange(n) % 23 == 5, np.inf, 1e8 * s)
    add(sx=inf, sy=-inf)
    return np.ascontiguousarray(np.stack(cols, axis=1))


def _random_tensors(rng: np.random.Generator, k: int, n: int) -> np.ndarray:
    """(6, k, n) smooth histories of random tensors, many near-uniaxial or hydrostatic."""
    t = np.arange(n)[None, None, :]
    base = rng.normal(size=(6, k, 1)) * 10.0 ** rng.uniform(5, 9, (1, k, 1))
    amp = rng.normal(size=(6, k, 1)) * 10.0 ** rng.uniform(4, 9, (1, k, 1))
    amp[:, ::3] *= np.array([1.0, 1e-7, 1e-7, 1e-7, 1e-7, 1e-7])[:, None, None]
    base[:3, 1::3] += 1e9  # near-hydrostatic offsets
    comp = base + amp * np.sin(2 * np.pi * t * rng.uniform(0.003, 0.08, (1, k, 1)))
    return np.ascontiguousarray(comp)


def test_bracket_holds_the_exact_value_on_hard_tensors() -> None:
    comp = _hard_tensors()
    lo, hi = _brackets(comp)
    eq = _exact(comp)
    finite = np.isfinite(eq)
    assert np.all(lo[finite] <= eq[finite]) and np.all(eq[finite] <= hi[finite])
    assert np.all(lo[~finite] == -np.inf) and np.all(hi[~finite] == np.inf)
    # informative where it should be: uniaxial (r = +-1) within 1e-6 of the value
    for i in (1, 2, 5):
        w = (hi[i] - lo[i])[np.abs(eq[i]) > 1e7]
        assert np.all(w <= 1e-6 * np.abs(eq[i][np.abs(eq[i]) > 1e7]))


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_bracket_holds_the_exact_value_on_random_tensors(seed: int) -> None:
    rng = np.random.default_rng(seed)
    comp = _random_tensors(rng, 60, 300)
    lo, hi = _brackets(comp)
    eq = _exact(comp)
    assert np.all(lo <= eq) and np.all(eq <= hi)


def _subsequence(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether ``a`` is ``b`` with some entries left out (in order, bits compared)."""
    it = iter(b.tolist())
    return all(any(x == y or (x != x and y != y) for y in it) for x in a.tolist())


@pytest.mark.parametrize("hard", [True, False])
def test_kept_values_are_exact_and_cover_the_turning_points(hard: bool) -> None:
    comp = _hard_tensors() if hard else _random_tensors(np.random.default_rng(3), 50, 500)
    _, k, n = comp.shape
    vals, counts = turning_eq.kept_equivalent(comp, n, "abs_max_principal")
    eq = _exact(comp)  # (k, n)
    tp = turning_points(eq.T, None)  # what rainflow needs, packed (rows: the most kept)
    pos = 0
    for i in range(k):
        v = vals[pos:pos + counts[i]]
        pos += counts[i]
        assert v[0] == eq[i, 0] or np.isnan(v[0]) and np.isnan(eq[i, 0])
        assert v[-1] == eq[i, -1] or np.isnan(v[-1]) and np.isnan(eq[i, -1])
        assert _subsequence(v, eq[i])  # exact values, in order
        m = np.unique(np.nonzero(np.diff(np.sign(np.diff(eq[i]))))[0] + 1)
        assert _subsequence(eq[i, m], v)  # every turning point (and flat sample) kept
    assert pos == vals.size
    if not hard:  # the bracket is tight: little beyond the turning points
        assert vals.size <= 1.5 * (tp.shape[0] * k)


def test_kept_equivalent_scratch_too_small_is_reallocated() -> None:
    comp = _random_tensors(np.random.default_rng(4), 30, 200)
    ref = turning_eq.kept_equivalent(comp, 200, "abs_max_principal")
    small = turning_eq.kept_equivalent(comp, 200, "abs_max_principal", np.empty(6 * 200))
    assert all(np.array_equal(a, b) for a, b in zip(ref, small, strict=True))


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), ties=st.booleans(), nans=st.booleans())
def test_feed_packed_equals_the_lock_step_counter(seed: int, ties: bool, nans: bool) -> None:
    """The same cycles (each history's in order), residues and lasts as the lock-step loop."""
    rng = np.random.default_rng(seed)
    k = int(rng.integers(1, 9))
    ref, new = (StreamingRainflow(k, capacity=4) for _ in range(2))
    for _ in range(4):
        n = int(rng.integers(1, 40))
        x = rng.normal(size=(n, k))
        if ties:
            x = np.round(x * 2.0)
        if nans:
            x[rng.random(x.shape) < 0.05] = np.nan
        ref._last = x[-1].copy()
        a = lock_step(ref, x)
        vals, counts = np.ascontiguousarray(x.T).ravel(), np.full(k, n)
        b = new.feed_packed(vals, counts, x[-1])
        order = np.argsort(a.series, kind="stable")
        for f in ("series", "s1", "s2", "count"):
            assert np.array_equal(getattr(a, f)[order], getattr(b, f), equal_nan=True)
        for i in range(k):
            assert np.array_equal(ref.residue(i), new.residue(i), equal_nan=True)
        assert np.array_equal(ref.last, new.last, equal_nan=True)
    rep = new.residue_cycles("repeated")  # compiled on a copy
    rep_ref = repeated_lock_step(ref)
    order = np.argsort(rep_ref.series, kind="stable")
    for f in ("series", "s1", "s2", "count"):
        assert np.array_equal(getattr(rep_ref, f)[order], getattr(rep, f), equal_nan=True)
    assert np.array_equal(ref.depth, new.depth)  # residue_cycles leaves the state alone


def test_feed_packed_part_of_the_counter_and_bad_shapes() -> None:
    rf = StreamingRainflow(5)
    cyc = rf.feed_packed(np.array([0.0, 3.0, 1.0, 2.0, 0.0, 5.0]), np.array([6]),
                         np.array([5.0]), start=3)
    # 0 3 1 2 0: (1, 2) closes; 0 3 0 5: (3, 0) closes; the residue 0 5
    assert cyc.series.tolist() == [3, 3]
    assert cyc.s1.tolist() == [1.0, 3.0] and cyc.s2.tolist() == [2.0, 0.0]
    assert rf.depth.tolist() == [0, 0, 0, 2, 0] and rf.residue(3).tolist() == [0.0, 5.0]
    with pytest.raises(ValueError, match="feed_packed"):
        rf.feed_packed(np.zeros(3), np.array([2]), np.zeros(1), start=4)
    with pytest.raises(ValueError, match="feed_packed"):
        rf.feed_packed(np.zeros(3), np.array([3]), np.zeros(1), start=5)


ENGINES = {"compiled": worker._Engine._exact_compiled, "numpy": exact_numpy,
           "block": exact_block}
"""The engine's block step: the product's, and the oracles' replacements of it."""


def _run(cfg: FatigueConfig, t, loads, cut: list[int], screen=None):
    names = list(loads)
    arr = np.stack([loads[c] for c in names], axis=1)
    live = worker.LiveFatigue(cfg, names, 40.0, screen=screen, total_samples=t.size)
    for a, b in zip(cut[:-1], cut[1:], strict=True):
        live.update(t[a:b], arr[a:b])
    return live


@pytest.mark.parametrize("kw", [
    {}, {"equivalent": "signed_von_mises", "method": "strain_life", "mean_stress": "swt",
         "residue": "half_cycles"}])
@pytest.mark.parametrize("screen", [None, 0.05])
def test_engines_give_the_same_bits(monkeypatch, kw, screen) -> None:
    """compiled (the product) == the numpy oracle == block (every sample: the reference),
    live in blocks of block_samples and batch, bit for bit."""
    cfg = FatigueConfig.from_dict({**COARSE, **kw, "block_samples": 300})
    t, loads = pave_like_loads(3.0, seed=4, static_n=6000, rms_n=4000)
    cut = [*range(0, t.size, 300), t.size]
    got = {}
    for eng, fn in ENGINES.items():
        monkeypatch.setattr(worker._Engine, "_exact_compiled", fn)
        got[eng] = (_run(cfg, t, loads, cut, screen).result(),
                    worker.analyse(t, loads, cfg, 40.0, screen=screen))
    for eng in ("numpy", "block"):
        for a, b in zip(got["compiled"], got[eng], strict=True):
            for f in FIELDS:
                assert np.array_equal(getattr(a, f), getattr(b, f), equal_nan=True), (eng, f)
            assert a.life_km == b.life_km and a.critical_node_id == b.critical_node_id


def test_noise_loads_keep_most_samples_and_the_same_bits(monkeypatch) -> None:
    """White-noise loads: most samples are turning points (the gather buffer grows)."""
    cfg = FatigueConfig.from_dict({**COARSE, "block_samples": 400})
    t, loads = pave_like_loads(1.0, seed=8, static_n=6000, rms_n=4000)
    rng = np.random.default_rng(8)
    loads = {c: v + rng.normal(size=v.size) * 2000.0 for c, v in loads.items()}
    cut = [*range(0, t.size, 400), t.size]
    got = {}
    for eng in ("compiled", "block"):
        monkeypatch.setattr(worker._Engine, "_exact_compiled", ENGINES[eng])
        got[eng] = _run(cfg, t, loads, cut).result()
    for f in FIELDS:
        assert np.array_equal(getattr(got["compiled"], f), getattr(got["block"], f))
    assert np.nanmin(got["block"].n_cycles) > 0.2 * t.size  # noise: cycles every few samples


@pytest.mark.parametrize("screen", [None, 0.1])
def test_live_fatigue_as_plain_data_continues_with_the_same_bits(screen) -> None:
    """A checkpoint holds LiveFatigue as plain data (:mod:`cosim.plaindata`: no compiled
    objects); decoded, it continues with the same bits."""
    cfg = FatigueConfig.from_dict({**COARSE, "block_samples": 200})
    t, loads = pave_like_loads(2.0, seed=7, static_n=6000, rms_n=4000)
    names = list(loads)
    arr = np.stack([loads[c] for c in names], axis=1)
    live = worker.LiveFatigue(cfg, names, 40.0, screen=screen, total_samples=t.size)
    half = 600
    for i in range(0, half, 200):
        live.update(t[i:i + 200], arr[i:i + 200])
    other = plaindata.decode(plaindata.encode(live))
    assert type(other) is worker.LiveFatigue
    for lf in (live, other):
        for i in range(half, t.size, 200):
            lf.update(t[i:i + 200], arr[i:i + 200])
    a, b = live.result(), other.result()
    for f in FIELDS:
        assert np.array_equal(getattr(a, f), getattr(b, f), equal_nan=True)


def test_kernels_compiled_before_the_first_block_not_in_the_step_loop() -> None:
    """Explicit signatures, compiled (or loaded from the cache) by warm_up, which loading the
    influence does (the live node: before ready); a block of the worker's types adds no
    specialisation (no compile later)."""
    worker.load_influence(FatigueConfig.from_dict(COARSE))
    kernels = (turning_eq._keep_gather, turning_eq._root1, counting._rainflow_packed,
               screening._bound_slots)
    before = [len(k.signatures) for k in kernels]
    assert before == [1, 1, 1, 1]
    comp = _random_tensors(np.random.default_rng(1), 8, 100)
    vals, counts = turning_eq.kept_equivalent(comp, 100, "abs_max_principal")
    StreamingRainflow(8).feed_packed(vals, counts, vals[np.cumsum(counts) - 1])
    inf = worker.load_influence(FatigueConfig.from_dict(COARSE))
    scr = screening.StressScreen(inf.coefficients, "abs_max_principal")
    F = np.random.default_rng(2).normal(size=(120, len(inf.case_names)))
    scr.block(F, np.arange(40), 25, probe=np.arange(40, 50))
    assert [len(k.signatures) for k in kernels] == before


def test_components_buffer_is_superpose_components() -> None:
    rng = np.random.default_rng(2)
    per = rng.normal(size=(7, 5, 6))
    F = rng.normal(size=(150, 5)) * 1e3
    buf, n = components_buffer(F, per, np.full(6 * 7 * 192 + 5, np.nan))
    assert n == 150 and buf.shape == (6, 7, 192) and buf.flags.c_contiguous
    assert np.array_equal(buf.transpose(0, 2, 1)[:, :n], superpose_components(F, per))
    with pytest.raises(ValueError, match="scratch"):
        components_buffer(F, per, np.zeros((6, 7 * 192)))
