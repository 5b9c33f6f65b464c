"""The one-process engine (``run.transport = "inprocess"``, issue #41): the same node models
stepped in one process give the distributed run's table and fatigue lives bit for bit."""

from __future__ import annotations

import filecmp
import json
from pathlib import Path

import pytest

from tests.conftest import ROOT, suscosim

CH3 = ROOT / "scenarios" / "ch3_step_quarter_car.toml"
CH6 = ROOT / "scenarios" / "thesis" / "ch6_realistic_qvm.toml"


def _run(scenario: Path, out: Path, *args: str) -> dict:
    res = suscosim("run", str(scenario), "--out", str(out), "--quiet", *args, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    return json.loads((out / "summary.json").read_text())


def _same(a: Path, b: Path, name: str) -> None:
    assert filecmp.cmp(a / name, b / name, shallow=False), f"{name} differs"


@pytest.mark.integration
@pytest.mark.parametrize("exchange", ["sequential", "parallel"])
def test_lumped_car_inprocess_table_is_the_distributed_one(tmp_path: Path,
                                                           exchange: str) -> None:
    sets = ("--set", "run.t_end=0.6", "--set", f'run.exchange="{exchange}"')
    dist = _run(CH3, tmp_path / "d", "--mode", "distributed", *sets)
    inp = _run(CH3, tmp_path / "i", "--inprocess", *sets)
    assert dist["mode"] == "distributed" and "transport" not in dist
    assert inp["mode"] == "monolithic" and inp["transport"] == "inprocess"
    assert inp["rows"] == dist["rows"] == 601
    for name in ("table.csv", "table.parquet"):
        _same(tmp_path / "d", tmp_path / "i", name)
    assert inp["coupling_energy_residual"] == dist["coupling_energy_residual"]


@pytest.mark.integration
def test_corner_with_live_fatigue_inprocess_is_the_distributed_one(tmp_path: Path) -> None:
    sets = ("--set", "road.length_m=3", "--set", "fatigue.block_samples=97")
    dist = _run(CH6, tmp_path / "d", "--mode", "distributed", *sets)
    inp = _run(CH6, tmp_path / "i", "--mode", "monolithic", *sets)  # the alias
    assert inp["transport"] == "inprocess" and "fatigue" in inp["nodes"]
    for name in ("table.csv", "table.parquet", "fatigue/damage_per_node.csv"):
        _same(tmp_path / "d", tmp_path / "i", name)
    for key in ("min_life_km", "max_damage", "critical_node_id", "min_life_repeats"):
        assert inp["fatigue"][key] == dist["fatigue"][key], key
    assert inp["fatigue"]["max_damage"] > 0


def test_what_the_engine_does_not_run_is_refused_with_exit_2(tmp_path: Path) -> None:
    res = suscosim("run", str(CH3), "--out", str(tmp_path / "r"), "--quiet", "--inprocess",
                   "--set", "run.t_end=0.1", "--set", "run.checkpoint_every_s=0.05")
    assert res.returncode == 2, res.stderr
    assert "run.checkpoint_every_s" in res.stderr and "inprocess" in res.stderr
