"""The plant node publishes the bump-stop force: ``plant/response/F_bs`` and the arm's
``plant/arm/bump_stop_{y,z}``, in a short monolithic run of the Ch. 4 realistic scenario
with the bumper's clearance closed down so that the 50 mm bump reaches it."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from cosim.table import read_table

from ..conftest import ROOT, suscosim


def test_realistic_run_records_the_bump_stop_force(tmp_path: Path) -> None:
    out = tmp_path / "run"
    res = suscosim("run", str(ROOT / "scenarios" / "ch4_qvm_realistic_bump_pothole.toml"),
                   "--out", str(out), "--mode", "monolithic", "--quiet",
                   "--set", "run.t_end=0.6", "--set", "vehicle.bump_stop_clearance=0.01",
                   "--set", "fatigue.live=false")  # the plant channels, not the FE
    assert res.returncode == 0, res.stderr + res.stdout
    assert json.loads((out / "summary.json").read_text())["status"] == "ok"
    table = read_table(out / "table.parquet")
    F_bs = np.asarray(table["plant/response/F_bs"], dtype=float)
    bz = np.asarray(table["plant/arm/bump_stop_z"], dtype=float)
    by = np.asarray(table["plant/arm/bump_stop_y"], dtype=float)
    theta = np.asarray(table["plant/state/arm_angle"], dtype=float)
    assert np.all(F_bs >= 0.0) and F_bs[:100].max() == 0.0  # clear before the bump
    assert F_bs.max() > 1000.0
    # the arm load is the same force, turned into the arm frame at t_k
    np.testing.assert_allclose(bz, -F_bs * np.cos(theta), rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(by, -F_bs * np.sin(theta), rtol=1e-6, atol=1e-6)
