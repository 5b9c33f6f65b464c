"""``run.coupling_h`` (multi-rate coupling, issue #41 item 4): the nodes exchange once per
coupling step, the plant keeps its own step (run.h / run.substeps) between."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cosim import scenario as sc
from cosim.errors import ScenarioError
from tests.conftest import ROOT, suscosim

CH3 = ROOT / "scenarios" / "ch3_step_quarter_car.toml"
CH6 = ROOT / "scenarios" / "thesis" / "ch6_realistic_qvm.toml"


def _run(*sets: str) -> dict:
    return sc.load(CH6, list(sets))["run"]


def test_the_coupling_step_becomes_the_communication_step_the_plant_step_stays() -> None:
    base = _run()  # h = 0.5 ms, 2 substeps: the plant steps 0.25 ms
    assert base["coupling_h"] == 0.0 and base["h"] == 0.0005 and base["substeps"] == 2
    for every, m in ((0.0005, 1), (0.001, 2), (0.002, 4)):
        run = _run(f"run.coupling_h={every}")
        assert run["h"] == every and run["substeps"] == 2 * m
        assert run["h"] / run["substeps"] == pytest.approx(0.00025, rel=1e-12)
        again = sc.validate_common({"run": dict(run)})["run"]  # a resolved scenario: as is
        assert (again["h"], again["substeps"]) == (run["h"], run["substeps"])


@pytest.mark.parametrize("bad", ["0.0007", "0.0002"])
def test_a_coupling_step_that_is_not_a_whole_multiple_of_h_is_refused(bad: str) -> None:
    with pytest.raises(ScenarioError, match="run.coupling_h.*whole multiple of run.h"):
        _run(f"run.coupling_h={bad}")


def test_an_adaptive_step_takes_no_coupling_step() -> None:
    with pytest.raises(ScenarioError, match="run.coupling_h"):
        sc.load(CH3, ['run.h="auto"', "run.coupling_h=0.002"])


@pytest.mark.integration
def test_a_corner_run_at_a_1_ms_coupling_step_reports_its_residual(tmp_path: Path) -> None:
    """The issue's check: the Ch 6 scenario with run.coupling_h = 0.001 runs and reports its
    coupling energy residual; the exchange is every 1 ms, so the table has one row a ms."""
    out = tmp_path / "r"
    res = suscosim("run", str(CH6), "--out", str(out), "--quiet", "--set",
                   "run.coupling_h=0.001", "--set", "road.length_m=2", "--set",
                   "fatigue.live=false", timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["h"] == 0.001 and summary["substeps"] == 4
    assert summary["rows"] == summary["n_steps"] + 1 == round(2 / (34 / 3.6) / 0.001) + 1
    resid = summary["coupling_energy_residual"]
    assert 0 < resid["total"] < 1 and set(resid) == {"total", "tyre", "damper"}
    assert "coupling energy residual" in res.stdout
