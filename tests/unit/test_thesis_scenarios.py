"""Every file under scenarios/thesis loads and validates (no runs): scenarios through the
runner's preflight, sweep files through ``suscosim sweep``'s point validation."""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import pytest

from cosim import scenario as sc
from orchestrator.runner import resolve
from orchestrator.sweep import load_sweep, validate_points

THESIS = Path(__file__).resolve().parents[2] / "scenarios" / "thesis"
FILES = sorted(THESIS.glob("*.toml"))


def test_the_thesis_studies_are_there():
    names = {f.stem for f in FILES}
    for required in ("ch3_tyre_step", "ch4_models", "ch5_lumped_random", "ch5_bump_pothole",
                     "ch6_fatigue"):
        assert required in names


@pytest.mark.parametrize("path", FILES, ids=[f.name for f in FILES])
def test_thesis_file_validates(path, tmp_path):
    if "sweep" in tomllib.loads(path.read_text()):
        sweep = load_sweep(path)
        assert sweep.points, "a sweep without points"
        validate_points(sweep, tmp_path)
        assert all(p.n_steps > 0 and p.fingerprint for p in sweep.points)
        assert len({p.id for p in sweep.points}) == len(sweep.points)
    else:
        scenario = resolve(copy.deepcopy(sc.load(path)), tmp_path / "run")
        assert scenario["run"]["n_steps"] > 0


def test_ch6_sweep_is_three_pave_seeds_and_the_bump_times_four_strategies():
    sweep = load_sweep(THESIS / "ch6_fatigue.toml")
    assert sweep.fatigue
    combos = {(p.params["road"], p.params["strategy"]) for p in sweep.points}
    assert combos == {(r, s) for r in ("pave_s1", "pave_s2", "pave_s3", "bump_pothole")
                      for s in ("passive", "tss1", "tss2", "tss3")}
    laws = {p.params["strategy"]: p.overrides["controller"]["law"] for p in sweep.points}
    assert laws == {"passive": "passive", "tss1": "tss1", "tss2": "tss2", "tss3": "tss3"}
