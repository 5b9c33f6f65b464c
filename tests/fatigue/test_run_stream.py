"""Batch fatigue read in row batches (#32): the streamed passes equal the whole-table path."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from cosim.errors import InputFileError
from nodes.fatigue import run_stream as rs
from nodes.fatigue.config import FatigueConfig
from nodes.fatigue.outputs import batch_outputs
from nodes.fatigue.synthetic import pave_like_loads
from nodes.fatigue.worker import analyse

COARSE = {"mesh_size_m": 0.03, "component": {"surface": "machined"}}


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
    from nodes.fatigue.counting import count_series
    from nodes.fatigue.pseudo_damage import rainflow_matrix

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
