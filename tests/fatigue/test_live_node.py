"""The live fatigue node: the recorder streams arm loads in blocks while the run goes on;
at the end the live result equals the batch worker on the recorded table."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from nodes.fatigue.config import FatigueConfig
from nodes.fatigue.run_dir import read_table, track_length
from nodes.fatigue.worker import analyse
from tests.conftest import ROOT, suscosim

REALISTIC = ROOT / "scenarios" / "ch4_qvm_realistic_bump_pothole.toml"


def _damage_csv(path: Path) -> dict[int, float]:
    with open(path, newline="") as fh:
        return {int(r["node_id"]): float(r["damage_per_pass"]) for r in csv.DictReader(fh)}


def _screened_csv(path: Path) -> set[int]:
    """Nodes the live screen left out (their cycles NaN: the damage is an upper bound)."""
    with open(path, newline="") as fh:
        return {int(r["node_id"]) for r in csv.DictReader(fh) if r["cycles"] == "nan"}


@pytest.mark.integration
@pytest.mark.parametrize("mode", ["distributed", "monolithic"])
def test_live_fatigue_equals_batch_on_the_recorded_loads(mode: str, tmp_path: Path) -> None:
    out = tmp_path / "run"
    res = suscosim("run", str(REALISTIC), "--out", str(out), "--quiet", "--mode", mode,
                   "--set", "run.t_end=1.2", "--set", "fatigue.block_samples=97",
                   timeout=240)
    assert res.returncode == 0, res.stdout + res.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert "fatigue" in summary["nodes"]
    live = json.loads((out / "fatigue" / "summary.json").read_text())
    assert live["source"] == "live"
    assert live["n_samples"] == summary["n_steps"] + 1  # every step, once
    # batch on the same loads, from the table the recorder wrote
    scenario = json.loads((out / "scenario.json").read_text())
    cfg = FatigueConfig.from_dict(scenario.get("fatigue"))
    t, loads = read_table(out)
    batch = analyse(t, loads, cfg, track_length(scenario, t))
    assert batch.max_damage > 0
    assert live["max_damage_per_pass"] == pytest.approx(batch.max_damage, rel=1e-9)
    assert live["critical_node_id"] == batch.critical_node_id
    assert live["min_life_km"] == pytest.approx(batch.life_km, rel=1e-9)
    per_node = _damage_csv(out / "fatigue" / "damage_per_node.csv")
    expect = dict(zip(batch.node_ids.tolist(), batch.damage.tolist(), strict=True))
    assert per_node.keys() == expect.keys()
    # the live node screens (fatigue.screen, 0.1): computed nodes as batch, the rest bounds
    out_ids = _screened_csv(out / "fatigue" / "damage_per_node.csv")
    assert live["screening"]["fraction"] == cfg.screen == 0.1
    assert live["screening"].get("screened_nodes", 0) == len(out_ids)
    ids = sorted(set(expect) - out_ids)
    np.testing.assert_allclose([per_node[i] for i in ids], [expect[i] for i in ids],
                               rtol=2e-6, atol=1e-30)
    assert all(per_node[i] >= expect[i] * (1 - 2e-6) for i in out_ids)
    assert all(expect[i] < 0.1 * batch.max_damage for i in out_ids)
    assert summary["fatigue"]["critical_node_id"] == batch.critical_node_id
    assert "fatigue (live)" in res.stdout


@pytest.mark.integration
def test_live_fatigue_off_and_refused_on_a_plant_without_arm_loads(tmp_path: Path) -> None:
    out = tmp_path / "off"
    res = suscosim("run", str(REALISTIC), "--out", str(out), "--quiet", "--mode", "monolithic",
                   "--set", "run.t_end=0.2", "--set", "fatigue.live=false")
    assert res.returncode == 0, res.stderr
    assert "fatigue" not in json.loads((out / "summary.json").read_text())["nodes"]
    assert not (out / "fatigue").exists()
    bad = suscosim("run", str(ROOT / "scenarios" / "ch3_step_quarter_car.toml"),
                   "--out", str(tmp_path / "bad"), "--set", "fatigue.live=true")
    assert bad.returncode == 2
    assert "fatigue.live" in bad.stderr and "arm loads" in bad.stderr


def test_a_node_computing_a_long_block_keeps_telling_the_orchestrator() -> None:
    """A block of the CAD arm at rest can take seconds (every sample kept): the fatigue node
    sends progress while it computes, so the clock does not blame a working node; after the
    block nothing more is sent (a node stuck elsewhere is still seen)."""
    import threading
    import time

    from cosim.participant import alive_while_busy

    sent: list[tuple[str, int]] = []

    class Part:
        rejected = 0
        node = "fatigue"

        def ctl(self, kind: str, k: int = -1, t: float = 0.0, **d: object) -> None:
            sent.append((kind, k))

    release = threading.Event()
    with alive_while_busy(Part(), 7, 0.0035, period_s=0.02):  # type: ignore[arg-type]
        deadline = time.monotonic() + 30.0
        while len(sent) < 3 and time.monotonic() < deadline:
            release.wait(0.01)  # "computing"
    assert len(sent) >= 3 and set(sent) == {("progress", 7)}
    n = len(sent)
    release.wait(0.2)  # ten periods after the block: silent
    assert len(sent) == n
