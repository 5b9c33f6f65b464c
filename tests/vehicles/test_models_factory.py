"""build_plant_model: model selection, parameters, and ScenarioError for bad input."""

import pytest

from cosim.errors import ScenarioError
from nodes.plant.models import build_plant_model


def test_builds_lumped_with_table_4_3():
    m = build_plant_model({"model": "quarter_car_lumped", "sprung_mass": 535,
                           "unsprung_mass": 47.75, "spring_stiffness": 31000})
    try:
        assert m.static_tyre_load()[0] == pytest.approx((535 + 47.75) * 9.81)
        info = m.info()
        assert info["wheel_x"] == [0.0] and info["wheel_track"] == [1]
    finally:
        m.close()


def test_builds_full_vehicle_axle_basis():
    m = build_plant_model({"model": "full_vehicle_7dof", "mass_basis": "axle"})
    try:
        assert m.n_corners == 4
        assert m.info()["body_mass"] == pytest.approx(935.0)
    finally:
        m.close()


@pytest.mark.parametrize("cfg,key", [
    ({"model": "bicycle"}, "vehicle.model"),
    ({}, "vehicle.model"),
    ({"model": "quarter_car_lumped", "sprung_mass": -1}, "vehicle.sprung_mass"),
    ({"model": "quarter_car_lumped", "sprung_mass": "heavy"}, "vehicle.sprung_mass"),
    ({"model": "quarter_car_lumped", "spring_rate": 1}, "vehicle.spring_rate"),
    ({"model": "full_vehicle_7dof", "mass_basis": "wheel"}, "vehicle.mass_basis"),
    ({"model": "quarter_car_double_wishbone", "body_mas": 535}, "vehicle.body_mas"),
])
def test_bad_vehicle_config(cfg, key):
    with pytest.raises(ScenarioError) as e:
        build_plant_model(cfg)
    assert e.value.key == key
