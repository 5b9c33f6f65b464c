"""Screening: the bound holds on exact counts, and the screened result's reported quantities
(the critical node, the ten most damaged, every node computed, the stress extremes) are the
unscreened ones bit for bit; left-out nodes carry bounds above their true damage."""

from __future__ import annotations

import numpy as np
import pytest

from nodes.fatigue.config import FatigueConfig
from nodes.fatigue.lib.counting import count_series
from nodes.fatigue.lib.damage import per_range_unsupported
from nodes.fatigue.lib.equivalent_stress import equivalent
from nodes.fatigue.lib.screening import StressScreen, damage_bound
from nodes.fatigue.lib.superposition import stress_history
from nodes.fatigue.synthetic import pave_like_loads
from nodes.fatigue.worker import analyse, load_influence
from tests.conftest import COARSE_ARM

from .oracle_miner import miner_per_node

COARSE = {"influence": str(COARSE_ARM)}  # a cheap arm, results shipped


@pytest.fixture(autouse=True)
def _cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("SUSCOSIM_CACHE", str(tmp_path_factory.getbasetemp() / "cache"))


@pytest.mark.parametrize("kw", [{}, {"equivalent": "signed_von_mises", "mean_stress": "swt",
                                     "residue": "half_cycles"}])
def test_the_bound_is_above_the_exact_envelope_variation_and_damage(kw):
    """The compiled bound against the exact history of every node."""
    cfg = FatigueConfig.from_dict({**COARSE, **kw})
    inf = load_influence(cfg)
    t, loads = pave_like_loads(1.5, seed=4, static_n=6000, rms_n=4000)
    F = np.stack([loads.get(f"plant/arm/{c}", np.zeros(t.size)) for c in inf.case_names], 1)
    e = equivalent(stress_history(F, inf.coefficients), cfg.equivalent)
    scr = StressScreen(inf.coefficients, cfg.equivalent)
    idx = np.arange(inf.n_nodes)
    hi, lo, tv = np.full(idx.size, -np.inf), np.full(idx.size, np.inf), np.zeros(idx.size)
    prev = None
    for i in range(0, t.size, 200):  # blocks with the previous sample first
        Fe = F[i:i + 200] if prev is None else np.vstack([prev, F[i:i + 200]])
        h, lo_b, v = scr.block(Fe, idx, 25)
        hi, lo, tv, prev = np.maximum(hi, h), np.minimum(lo, lo_b), tv + v, F[i:i + 200][-1]
    assert np.all(hi >= e.max(0)) and np.all(lo <= e.min(0))
    assert np.all(tv >= np.abs(np.diff(e, axis=0)).sum(0))
    U = damage_bound(hi, lo, tv, cfg.material, cfg.method, cfg.mean_stress,
                     cfg.endurance)
    for node in np.argsort(U)[::-1][:5].tolist() + [0, inf.n_nodes // 2]:
        cyc = count_series(e[:, node], cfg.residue)
        d = miner_per_node(cyc, 1, cfg.material, cfg.method, cfg.mean_stress,
                           cfg.endurance)[0]
        assert 0 < d <= U[node]


def test_screened_reported_quantities_are_the_unscreened_bit_for_bit():
    cfg = FatigueConfig.from_dict({**COARSE, "block_samples": 250})
    t, loads = pave_like_loads(5.0, seed=2, static_n=6000, rms_n=4000)
    ref = analyse(t, loads, cfg, 50.0, screen=None)
    res = analyse(t, loads, cfg, 50.0, screen=0.01)
    out = res.screened
    assert out is not None and 0 < out.sum() < out.size
    assert res.critical_node_id == ref.critical_node_id and res.life_km == ref.life_km
    assert res.summary()["top_nodes"] == ref.summary()["top_nodes"]
    for f in ("eq_stress_max_pa", "eq_stress_min_pa", "critical_eq_range_max_pa"):
        assert res.summary()[f] == ref.summary()[f]
    np.testing.assert_array_equal(res.damage[~out], ref.damage[~out])
    np.testing.assert_array_equal(res.n_cycles[~out], ref.n_cycles[~out])
    # left out: below f of the largest damage, its bound above its true damage
    assert np.all(ref.damage[out] < 0.01 * ref.max_damage)
    assert np.all(res.damage[out] >= ref.damage[out]) and np.all(np.isnan(res.n_cycles[out]))
    assert res.summary()["screening"]["screened_nodes"] == int(out.sum())


def test_screening_is_off_where_the_bound_is_not_proven():
    cfg = FatigueConfig.from_dict({**COARSE, "method": "strain_life"})
    assert "strain_life" in per_range_unsupported(cfg.material, cfg.method, cfg.mean_stress)
    t, loads = pave_like_loads(0.5, seed=1)
    r = analyse(t, loads, cfg, 5.0, screen=0.01)
    assert not r.screened.any() and "strain_life" in r.screening["note"]


@pytest.mark.integration
def test_screened_equals_unscreened_on_a_ch6_pave_run_of_the_cad_arm(tmp_path):
    """Issue #28: on a realistic-corner run of Chapter 6 (the pave, seed 1, TSS2; 6 m, the
    built-in CAD arm, 13 778 assessed nodes), the screened engine leaves nodes out and gives
    the unscreened lives, critical node and ten most damaged nodes, bit for bit, batch and
    live (blocks of block_samples)."""
    from nodes.fatigue.run_dir import read_table, track_length
    from nodes.fatigue.worker import LiveFatigue
    from tests.conftest import ROOT, suscosim

    run = tmp_path / "pave"
    res = suscosim("run", str(ROOT / "scenarios" / "thesis" / "ch6_realistic_qvm.toml"),
                   "--mode", "monolithic", "--quiet", "--out", str(run),
                   "--set", "road.seed=1", "--set", "road.length_m=6",
                   "--set", 'controller={law="tss2", preset="realistic", B=0.8, G=0.001, '
                            'velocity="damper"}', "--set", "fatigue.live=false", timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    import json

    scenario = json.loads((run / "scenario.json").read_text())
    cfg = FatigueConfig.from_dict({**scenario.get("fatigue", {}), "block_samples": 97})
    t, loads = read_table(run)
    L = track_length(scenario, t)
    ref = analyse(t, loads, cfg, L, screen=None)
    assert ref.node_ids.size > 10_000  # the CAD arm
    names = list(loads)
    arr = np.stack([loads[c] for c in names], axis=1)
    live = LiveFatigue(cfg, names, L, screen=0.01, total_samples=t.size)
    for i in range(0, t.size, cfg.block_samples):
        live.update(t[i:i + cfg.block_samples], arr[i:i + cfg.block_samples])
    for res_s in (analyse(t, loads, cfg, L, screen=0.01), live.result()):
        out = res_s.screened
        assert out is not None and out.sum() > 0.2 * out.size  # the screen drops nodes
        assert res_s.critical_node_id == ref.critical_node_id
        assert res_s.life_km == ref.life_km and res_s.max_damage == ref.max_damage
        top_ref = np.argsort(ref.damage)[::-1][:10]
        top = np.argsort(res_s.damage)[::-1][:10]
        np.testing.assert_array_equal(top, top_ref)
        np.testing.assert_array_equal(res_s.damage[top], ref.damage[top_ref])
        assert res_s.summary()["top_nodes"] == ref.summary()["top_nodes"]
        np.testing.assert_array_equal(res_s.damage[~out], ref.damage[~out])
        assert np.all(res_s.damage[out] >= ref.damage[out])
        assert np.all(ref.damage[out] < 0.01 * ref.max_damage)


def test_compiled_bound_of_kept_slots_equals_a_fresh_gather_as_the_set_changes():
    """StressScreen.bounds_kept (the nodes' table columns kept in slots between blocks, nodes
    leaving and joining) gives each node the bound a fresh screen, which gathers them anew,
    gives it, bit for bit (a node's lanes never mix with another's)."""
    from nodes.fatigue.lib.screening import load_stats

    cfg = FatigueConfig.from_dict(COARSE)
    inf = load_influence(cfg)
    t, loads = pave_like_loads(0.6, seed=3, static_n=6000, rms_n=4000)
    F = np.stack([loads.get(f"plant/arm/{c}", np.zeros(t.size)) for c in inf.case_names], 1)
    scr = StressScreen(inf.coefficients, cfg.equivalent)
    scr.block(F[:100], np.arange(5), 25)  # axes set, tables built
    assert scr.V is not None
    rng = np.random.default_rng(7)
    idx = np.sort(rng.choice(inf.n_nodes, inf.n_nodes // 2, replace=False))
    for i in range(0, 300, 60):
        stats = load_stats(F[i:i + 61], scr.V, 25)
        got = scr.bounds_kept(stats, idx, False)
        fresh = StressScreen(inf.coefficients, cfg.equivalent)
        fresh.set_axes(F[:100])
        ref = fresh.bounds_kept(stats, idx, False)
        for a, b in zip(got, ref, strict=True):
            np.testing.assert_array_equal(a, b)
        assert sorted(scr.slot_node.tolist()) == sorted(idx.tolist())
        keep = rng.random(idx.size) > 0.2  # some leave, others join (in any order)
        idx = np.union1d(idx[keep], rng.choice(inf.n_nodes, 40, replace=False))
        idx = rng.permutation(idx)
