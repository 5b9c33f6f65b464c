"""Batch fatigue read in row batches (#32): the streamed passes equal the whole-table path."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from cosim.errors import InputFileError
from nodes.fatigue import run_stream as rs
from nodes.fatigue.config import FatigueConfig
from nodes.fatigue.synthetic import pave_like_loads
from nodes.fatigue.worker import analyse
from tests.conftest import COARSE_ARM
from tests.fatigue.whole_outputs import batch_outputs

COARSE = {"influence": str(COARSE_ARM),  # a cheap arm, results shipped
          "component": {"surface": "machined"}}


@pytest.fixture(autouse=True)
def _cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("SUSCOSIM_CACHE", str(tmp_path_factory.getbasetemp() / "cache"))


def _batches(t, loads, rows):
    def it():
        for i in range(0, t.size, rows):
            yield t[i:i + rows], {c: v[i:i + rows] for c, v in loads.items()}
    return it


def test_streamed_equals_whole(tmp_path):
    """Batches of 700 rows (not a multiple of block_samples = 500): damage, extremes, cycles,
    S-N method lives and rainflow matrices bit for bit; pseudo-damage to 1e-13."""
    cfg = FatigueConfig.from_dict(COARSE)
    t, loads = pave_like_loads(6.0, seed=3, static_n=6000, rms_n=4000)
    whole = analyse(t, loads, cfg, 40.0)
    _files, extra = batch_outputs(t, loads, cfg, 40.0, whole, lambda _m: None)
    b = _batches(t, loads, 700)
    s = rs.scan(b, "table", cfg.residue)
    assert s.n == t.size and s.duration_s == whole.duration_s
    res, methods, matrices = rs.analyse_streamed(b, cfg, 40.0, s, lambda _m: None)
    for k in ("damage", "eq_max", "eq_min", "eq_range_max", "n_cycles"):
        assert np.array_equal(getattr(res, k), getattr(whole, k)), k
    assert res.summary() == whole.summary()
    assert methods == extra["sn_methods"] and methods is not None
    from nodes.fatigue.lib.counting import count_series
    from nodes.fatigue.lib.pseudo_damage import rainflow_matrix

    for c, v in loads.items():
        assert matrices[c] == rainflow_matrix(count_series(v, cfg.residue)), c
    got = {p.channel: p for p in rs.pseudo_damage_of(s)}
    for p in extra["pseudo_damage"]["channels"]:
        q = got[p["channel"]]
        assert q.cycles == p["cycles"] and q.max_range == p["max_range"]
        assert q.pseudo_damage == pytest.approx(p["pseudo_damage"], rel=1e-13, abs=0)
    # the critical-node files: streamed writer against the whole-table writer
    w_whole, _ = batch_outputs(t, loads, cfg, 40.0, whole, lambda _m: None)
    w_str, _ = rs.outputs_streamed(b, cfg, s, res, methods, matrices, lambda _m: None)
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    w_whole(tmp_path / "a")
    w_str(tmp_path / "b")
    for name in ("critical_stress.csv", "rainflow_matrix.csv", "sn_plot.json"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()


def test_scan_names_the_bad_sample():
    t, loads = pave_like_loads(4.0, seed=1)
    loads["plant/arm/ball_joint_z"][1234] = np.nan
    loads["plant/arm/ball_joint_z"][1500] = np.inf
    with pytest.raises(InputFileError) as e:
        rs.scan(_batches(t, loads, 300), "table.parquet", "repeated", "run/table")
    assert "'plant/arm/ball_joint_z' sample 1234" in str(e.value)
    assert "2 such sample(s)" in str(e.value) and "run/table" in str(e.value)
    t2 = t.copy()
    t2[600] = t2[599]
    with pytest.raises(InputFileError, match="not strictly increasing"):
        rs.scan(_batches(t2, pave_like_loads(4.0, seed=1)[1], 300), "table.parquet",
                "repeated")


@pytest.mark.long  # memory growth: 2 and 20 passes under tracemalloc
def test_scan_memory_does_not_grow_with_the_history():
    """Pass 1 over 10x the samples: traced peak within 20 % (a batch and the residues)."""
    t, loads = pave_like_loads(4.0, seed=4)

    def repeated(times):
        def it():
            for r in range(times):
                yield t + r * (t[-1] + t[1]), loads
        return it

    peaks = []
    for times in (2, 20):
        tracemalloc.start()
        rs.scan(repeated(times), "table", "repeated")
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    assert peaks[1] < 1.2 * peaks[0], peaks


def test_sn_spectrum_counts_the_cycles_at_or_above_each_level():
    """The S-N plot's spectrum by level equals the cycles' own count at or above each level
    (infinite σar, a mean past Su, counted above all), in any order of the cycles."""
    from nodes.fatigue.lib.counting import Cycles, count_series
    from nodes.fatigue.lib.mean_stress import equivalent_amplitude
    from nodes.fatigue.outputs import SnSpectrum

    cfg = FatigueConfig.from_dict({**COARSE, "mean_stress": "goodman"})
    mat = cfg.material
    rng = np.random.default_rng(5)
    eq = np.cumsum(rng.normal(size=20_000)) * 4e6 + 1e8
    eq[5000] = 1.5 * mat.Su  # cycles with a mean past Su: infinite σar
    eq[5001] = -0.5 * mat.Su
    cyc = count_series(eq, cfg.residue)
    sar = equivalent_amplitude(0.5 * cyc.range, cyc.mean, cfg.mean_stress, mat.Su, mat.sf)
    assert not np.all(np.isfinite(sar))
    whole = SnSpectrum(cfg)
    whole.add(cyc)
    levels, cum = whole.cumulative()
    assert levels.size > 50
    for S, c in zip(levels, cum, strict=True):
        assert c == float(np.sum(cyc.count[~np.isfinite(sar) | (sar >= S)])), S
    parts = SnSpectrum(cfg)
    order = rng.permutation(len(cyc))
    for i in range(0, order.size, 333):
        j = order[i:i + 333]
        parts.add(Cycles(cyc.series[j], cyc.s1[j], cyc.s2[j], cyc.count[j]))
    assert all(np.array_equal(a, b) for a, b in zip(parts.cumulative(), (levels, cum),
                                                    strict=True))


@pytest.mark.long  # memory growth: 1, 8 and 40 repeats under tracemalloc
def test_critical_node_passes_memory_does_not_grow(tmp_path):
    """Passes 3 and 4 (critical_stress.csv, the S-N spectrum, the node's matrix) over 5x the
    samples (12 000 to 60 000): traced peak within 20 % (the equivalent stress not kept)."""
    cfg = FatigueConfig.from_dict(COARSE)
    t, loads = pave_like_loads(3.0, seed=6)
    res = analyse(t, loads, cfg, 40.0)

    def repeated(times):
        def it():
            for r in range(times):
                yield t + r * (t[-1] + t[1]), loads
        return it

    peaks = []
    for times in (1, 8, 40):  # the first a warm-up (matplotlib's imports and caches)
        b = repeated(times)
        s = rs.scan(b, "table", cfg.residue)
        write, _ = rs.outputs_streamed(b, cfg, s, res, None, {}, lambda _m: None)
        out = tmp_path / str(times)
        out.mkdir()
        tracemalloc.start()
        write(out)
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    assert peaks[2] < 1.2 * peaks[1], peaks  # 37 % more when eq was kept whole (65bbfeb)


def test_a_corners_batches_are_its_own_arm_columns_not_the_front_lefts(tmp_path) -> None:
    """A four-corner run's table holds plant/arm (the front left's) beside plant/arm_<corner>:
    ``suscosim fatigue RUN`` with ``corner = "RL"`` reads the rear left's columns, named as
    the lower arm's (plant/arm/...), the live node's channel (was: the front left's)."""
    fields = ["ball_joint_x", "ball_joint_z"]
    cols = ["k", "t", *(f"plant/arm/{f}" for f in fields),
            *(f"plant/arm_RL/{f}" for f in fields)]
    rows = [[k, k * 1e-3, 1.0 + k, 2.0 + k, -1.0 - k, -2.0 - k] for k in range(50)]
    src = tmp_path / "table.csv"
    src.write_text(",".join(cols) + "\n" + "\n".join(",".join(map(str, r)) for r in rows))
    t, loads = (np.concatenate(x) for x in zip(*(
        (b_t, np.column_stack([b[f"plant/arm/{f}"] for f in fields]))
        for b_t, b in rs.table_batches(src, rows=16, channel="arm_RL")()), strict=True))
    assert t.tolist() == [k * 1e-3 for k in range(50)]
    assert loads[:, 0].tolist() == [-1.0 - k for k in range(50)]
    assert loads[:, 1].tolist() == [-2.0 - k for k in range(50)]
