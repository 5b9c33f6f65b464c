"""The Chapter 4 scenarios build: vehicle, tyre and road sections are valid."""

import pathlib

import pytest

from nodes.plant.models import build_plant_model
from nodes.tyre_road.config import build_road, build_tyre

tomllib = pytest.importorskip("tomllib")  # Python >= 3.11

SCENARIOS = sorted((pathlib.Path(__file__).parents[2] / "scenarios").glob("ch4_*.toml"))


def test_there_are_ch4_scenarios():
    assert len(SCENARIOS) >= 5


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.name)
def test_scenario_sections_build(path):
    cfg = tomllib.loads(path.read_text())
    road = build_road(cfg["road"])
    tyre = build_tyre(cfg["tyre"])
    assert road.speed == pytest.approx(34 / 3.6)
    assert tyre.k_t == 239000.0
    assert cfg["run"]["t_end"] >= road.duration_s - 1e-9
    assert cfg["controller"]["law"] == "passive"
    model = build_plant_model(cfg["vehicle"])
    try:
        assert len(model.static_tyre_load()) == model.n_corners
    finally:
        model.close()
