"""A user's corner file through a distributed run (real node processes over Zenoh), with no
code change: ``--set vehicle.corner="FILE"``."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from nodes.plant.models import build_plant_model

from ..conftest import ROOT, suscosim

pytestmark = pytest.mark.integration

WIDE = Path(__file__).with_name("corners") / "wide_track.toml"


def test_a_distributed_run_takes_the_corner_file(tmp_path):
    out = tmp_path / "run"
    res = suscosim("run", str(ROOT / "scenarios" / "ch4_qvm_realistic_bump_pothole.toml"),
                   "--out", str(out), "--quiet", "--set", "run.t_end=0.2",
                   "--set", f'vehicle.corner="{WIDE}"', timeout=180)
    assert res.returncode == 0, res.stdout + res.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "ok" and summary["mode"] == "distributed"
    scenario = json.loads((out / "scenario.json").read_text())
    assert scenario["vehicle"]["corner"] == str(WIDE)
    with (out / "table.csv").open() as f:
        row0 = next(csv.DictReader(f))
    # the plant node built this corner: its static torsion-bar preload and tyre load at t = 0
    # (the scenario's mass keys override the file's; the hardpoints are the file's)
    wide = build_plant_model(scenario["vehicle"])
    builtin = build_plant_model({k: v for k, v in scenario["vehicle"].items()
                                 if k != "corner"})
    try:
        assert float(row0["plant/arm/torsion_bar_mx"]) == pytest.approx(wide.tau0, rel=1e-9)
        assert abs(wide.tau0 - builtin.tau0) > 50.0  # the longer lever: ~9 % more preload
        assert float(row0["plant/response/F_t"]) == pytest.approx(
            float(wide.static_tyre_load()[0]), rel=1e-12)
    finally:
        wide.close()
        builtin.close()
