"""Worker: config validation, imported tables, batch == live, run folder and CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

from cosim.errors import InputFileError, ScenarioError
from nodes.fatigue.config import FatigueConfig
from nodes.fatigue.synthetic import pave_like_loads
from nodes.fatigue.worker import LiveFatigue, analyse
from orchestrator.fatigue_cli import main
from tests.conftest import COARSE_ARM

COARSE = {"influence": str(COARSE_ARM)}  # a cheap arm, results shipped


@pytest.fixture(autouse=True)
def _cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("SUSCOSIM_CACHE", str(tmp_path_factory.getbasetemp() / "cache"))


@pytest.mark.parametrize("d,key", [
    ({"method": "magic"}, "fatigue.method"),
    ({"equivalent": "tresca"}, "fatigue.equivalent"),
    ({"mean_stress": "walker"}, "fatigue.mean_stress"),
    ({"material": {"Su": -1}}, "fatigue.material.Su"),
    ({"material": {"zz": 1}}, "fatigue.material.zz"),
    ({"mesh_size_m": "fine"}, "fatigue.mesh_size_m"),
    ({"influence": "tables/", "mapping": {}}, "fatigue.mapping"),
    ({"block_samples": 0}, "fatigue.block_samples"),
    ({"colour": "red"}, "fatigue.colour"),
])
def test_config_errors_name_the_key(d, key):
    with pytest.raises(ScenarioError) as e:
        FatigueConfig.from_dict(d)
    assert e.value.key == key


def test_config_material_override():
    cfg = FatigueConfig.from_dict({"material": {"sf'": 2.0e9, "Se": 5e8}})
    assert cfg.material.sf == 2.0e9 and cfg.material.Se == 5e8


@pytest.mark.parametrize("kw", [
    {}, {"equivalent": "signed_von_mises", "method": "strain_life", "mean_stress": "swt",
         "residue": "half_cycles"}])
def test_live_equals_batch_random_blocks(kw):
    """Unscreened, a node's damage is the same bits however the history is cut (its cycles'
    damages summed in the order they close; superposition per node of fixed shape)."""
    cfg = FatigueConfig.from_dict({**COARSE, **kw})
    t, loads = pave_like_loads(4.0, seed=2, static_n=6000, rms_n=4000)
    batch = analyse(t, loads, cfg, 40.0, screen=None)
    channels = list(loads)
    live = LiveFatigue(cfg, channels, track_length_m=40.0, screen=None)
    rng = np.random.default_rng(5)
    i = 0
    arr = np.stack([loads[c] for c in channels], axis=1)
    while i < t.size:
        b = int(rng.integers(1, 700))
        if rng.random() < 0.5:
            live.update(t[i:i + b], arr[i:i + b])
        else:
            live.update(t[i:i + b], {c: loads[c][i:i + b] for c in channels})
        i += b
    res = live.result()
    assert batch.max_damage > 0
    np.testing.assert_array_equal(res.damage, batch.damage)
    np.testing.assert_array_equal(res.n_cycles, batch.n_cycles)
    np.testing.assert_array_equal(res.eq_range_max, batch.eq_range_max)
    assert res.critical_node == batch.critical_node
    assert res.life_km == batch.life_km
    assert res.duration_s == pytest.approx(batch.duration_s)


def test_screened_live_in_blocks_of_block_samples_is_the_batch_bit_for_bit():
    """Screening on: the live engine fed the blocks the batch cuts
    (``block_samples`` from the first sample, as the live node does) leaves out the same
    nodes with the same bounds; fed other blocks, the reported quantities still agree."""
    cfg = FatigueConfig.from_dict({**COARSE, "block_samples": 300})
    t, loads = pave_like_loads(4.0, seed=2, static_n=6000, rms_n=4000)
    batch = analyse(t, loads, cfg, 40.0, screen=0.01)
    assert batch.screened is not None and batch.screened.any()
    channels = list(loads)
    arr = np.stack([loads[c] for c in channels], axis=1)
    live = LiveFatigue(cfg, channels, track_length_m=40.0, screen=0.01,
                       total_samples=t.size)
    for i in range(0, t.size, 300):
        live.update(t[i:i + 300], arr[i:i + 300])
    res = live.result()
    np.testing.assert_array_equal(res.damage, batch.damage)
    np.testing.assert_array_equal(res.screened, batch.screened)
    np.testing.assert_array_equal(res.eq_max, batch.eq_max)
    assert res.summary()["top_nodes"] == batch.summary()["top_nodes"]
    other = LiveFatigue(cfg, channels, track_length_m=40.0, screen=0.01)
    rng = np.random.default_rng(7)
    i = 0
    while i < t.size:
        b = int(rng.integers(1, 700))
        other.update(t[i:i + b], arr[i:i + b])
        i += b
    odd = other.result()
    assert odd.summary()["top_nodes"] == batch.summary()["top_nodes"]
    assert odd.critical_node_id == batch.critical_node_id
    assert odd.life_km == batch.life_km
    both = ~odd.screened & ~batch.screened
    np.testing.assert_array_equal(odd.damage[both], batch.damage[both])


def test_life_scales_and_critical_node_at_notch():
    cfg = FatigueConfig.from_dict({**COARSE, "repeats_basis_m": 100.0})
    t, loads = pave_like_loads(3.0, seed=1, static_n=6000, rms_n=4000)
    r = analyse(t, loads, cfg, 30.0)
    assert r.life_repeats == pytest.approx(1 / r.damage.max())
    assert r.life_km == pytest.approx(r.life_repeats * 0.030)
    assert r.life_repeats_basis == pytest.approx(r.life_km * 10)
    # doubling every load raises damage by more than 2^k, k = -1/b: 3.32 on the default
    # component curve (issue #12; 11.5 on the old material line, when this said 2**8)
    r2 = analyse(t, {k: 2 * v for k, v in loads.items()}, cfg, 30.0)
    assert r2.max_damage > 2**3.3 * r.max_damage
    # the critical node is an assessed node (outside the joints' zones), off the hubs' faces
    from nodes.fatigue.parts import load_part
    from nodes.fatigue.worker import load_influence

    inf = load_influence(cfg)
    assert inf.node_xyz is not None
    assert np.any(np.all(inf.node_xyz == r.critical_xyz, axis=1))
    for j in load_part(COARSE_ARM).joints:
        assert np.hypot(*(np.asarray(r.critical_xyz) - j.centre)[:2]) > j.radius
    json.loads(json.dumps(r.summary()))


def _write_case(path, stresses, header=True):
    lines = ["NODE,SX,SY,SZ,SXY,SYZ,SXZ"] if header else []
    lines += [f"{i + 1}," + ",".join(f"{v:.9e}" for v in row) for i, row in enumerate(stresses)]
    path.write_text("\n".join(lines) + "\n")


def test_imported_tables_appendix_v_mapping(tmp_path):
    # Three cases as in App V: ANSYS FX <-> load FY, FZ <-> FX, FY <-> FZ.
    rng = np.random.default_rng(0)
    c = rng.normal(size=(3, 42, 6)) * 1e4
    _write_case(tmp_path / "LCase1-CompStress12FX.csv", c[0])
    _write_case(tmp_path / "LCase2-CompStress12FZ.csv", c[1])
    _write_case(tmp_path / "LCase3-CompStress12FY.csv", c[2], header=False)
    cfg = FatigueConfig.from_dict({
        "influence": str(tmp_path), "nodes": "all", "mean_stress": "none",
        "equivalent": "signed_von_mises",
        "mapping": {"plant/arm/ball_joint_y": "LCase1-CompStress12FX.csv",
                    "plant/arm/ball_joint_x": "LCase2-CompStress12FZ.csv",
                    "plant/arm/ball_joint_z": {"file": "LCase3-CompStress12FY.csv",
                                               "scale": 1.0}}})
    t = np.arange(2000) * 0.002
    FX, FY, FZ = (rng.normal(size=t.size) * 1e3 for _ in range(3))
    r = analyse(t, {"plant/arm/ball_joint_x": FX, "plant/arm/ball_joint_y": FY,
                    "plant/arm/ball_joint_z": FZ}, cfg, 10.0)
    # independent: App V loop, Sxt(:, i) = SxLC1(i) FY + SxLC2(i) FX + SxLC3(i) FZ
    from nodes.fatigue.lib.counting import count_series
    from nodes.fatigue.lib.equivalent_stress import signed_von_mises

    from .oracle_miner import miner_per_node
    node = 5
    s = c[0, node] * FY[:, None] + c[1, node] * FX[:, None] + c[2, node] * FZ[:, None]
    cyc = count_series(signed_von_mises(s), "repeated")
    d = miner_per_node(cyc, 1, cfg.material, "stress_life", "none")[0]
    assert r.damage[node] == pytest.approx(d, rel=1e-10)


def test_imported_bad_csv(tmp_path):
    (tmp_path / "a.csv").write_text("SX,SY\n1,2,3,4,5,6\n1,2,3,x,5,6\n")
    cfg = FatigueConfig.from_dict({"influence": str(tmp_path), "mapping": {"ball_joint_z":
                                                                           "a.csv"}})
    with pytest.raises(InputFileError) as e:
        analyse(np.arange(3.0), {"ball_joint_z": np.zeros(3)}, cfg, 1.0)
    assert e.value.line == 3
    (tmp_path / "a.csv").write_text("1,2,3\n")
    with pytest.raises(InputFileError):
        analyse(np.arange(3.0), {"ball_joint_z": np.zeros(3)}, cfg, 1.0)


def test_run_dir_and_cli(tmp_path, capsys):
    import pyarrow as pa
    import pyarrow.parquet as pq
    t, loads = pave_like_loads(2.0, seed=3)
    pq.write_table(pa.table({"t": t, **loads}), tmp_path / "table.parquet")
    (tmp_path / "scenario.json").write_text(json.dumps(
        {"road": {"speed_kmh": 36.0}, "run": {"t_end": 2.0}, "fatigue": COARSE}))
    assert main([str(tmp_path), "--mean-stress", "swt"]) == 0
    out = capsys.readouterr().out
    assert "min life" in out
    # a what-if (an override) goes to fatigue-<settings hash>/ (run_dir.results_folder)
    (res,) = [p for p in tmp_path.glob("fatigue-*") if p.is_dir()]
    summary = json.loads((res / "summary.json").read_text())
    assert summary["track_length_m"] == pytest.approx(20.0)
    assert summary["config"]["mean_stress"] == "swt"
    rows = (res / "damage_per_node.csv").read_text().splitlines()
    assert len(rows) == summary["n_nodes"] + 1
    assert (res / "damage_map.png").stat().st_size > 10_000
    assert main([str(tmp_path), "--set", "material.b=0.2"]) == 2
    assert main([str(tmp_path / "missing")]) == 2
    (tmp_path / "scenario.json").write_text("{not json")
    assert main([str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.count("\n") == 3


def test_every_fatigue_key_is_documented_in_docs_fatigue_keys():
    """The user reference of the keys (docs/fatigue_keys.md) names every key the config reads."""
    from pathlib import Path

    from nodes.fatigue.config import FATIGUE_KEYS
    from nodes.fatigue.strength_sections import COMPONENT_KEYS, FKM_KEYS

    text = (Path(__file__).parents[2] / "docs" / "fatigue_keys.md").read_text()
    rows = {line.split("|")[1].strip() for line in text.splitlines() if line.startswith("| `")}
    assert {f"`{k}`" for k in FATIGUE_KEYS + COMPONENT_KEYS} <= rows
    assert all(f"`{k}`" in text for k in FKM_KEYS)
