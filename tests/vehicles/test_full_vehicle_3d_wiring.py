"""The 3-D tyre's wiring (#31 item 2): the tyre/road node's Magic Formula step from the
four-corner vehicle's published state, the plant factory's ``driver`` table, the per-corner
arm channels and their schema."""

from __future__ import annotations

import numpy as np
import pytest

from cosim import schema
from cosim.errors import ScenarioError
from nodes.plant.models import build_plant_model
from nodes.tyre_road.node import TyreRoad

ROAD = {"type": "events", "speed_kmh": 50.0, "length_m": 50.0,
        "events": [{"type": "bump", "height": 0.05, "length": 1.0, "x_start": 40.0}]}


@pytest.fixture(scope="module")
def car():
    m = build_plant_model({"model": "full_vehicle_double_wishbone", "speed_kmh": 50.0,
                           "driver": {"speed": [[0.0, 13.889], [0.2, 13.889],
                                                [1.2, 6.04]], "brake_balance": 0.72}})
    yield m
    m.close()


def test_the_tyre_node_answers_the_published_state_with_road_plane_forces(car):
    scen = {"road": ROAD, "tyre": {"model": "magic_formula", "stiffness": 239000.0},
            "run": {"t_end": 1.0, "h": 0.002}}
    node = TyreRoad(scen, {"info": {"plant": car.info()}})
    st = car.state()
    out = node.step(0, 0.0, {"plant/state": st})
    assert out["F_t"] == pytest.approx(car.static_tyre_load(), rel=1e-9)
    assert np.abs(out["Fx"]).max() < 200.0 and np.abs(out["kappa"]).max() < 1e-3
    for key in ("Fx", "Fy", "Mz", "kappa", "alpha"):  # declared once, in the schema
        assert key in {f.name for f in schema.BY_NAME["tyre_road/force"].fields}
    for key in ("vx_wc", "vy_wc", "omega_w", "gamma", "x_wc", "r_l", "u", "w_yaw"):
        assert key in {f.name for f in schema.BY_NAME["plant/state"].fields}, key
        assert key in st, key


def test_a_vehicle_without_wheel_kinematics_is_refused_by_name():
    scen = {"road": ROAD, "tyre": {"model": "magic_formula"}, "run": {"t_end": 1.0, "h": 0.002}}
    node = TyreRoad(scen, {"info": {"plant": {"static_tyre_load": [5000.0]}}})
    with pytest.raises(ScenarioError, match="full_vehicle_double_wishbone"):
        node.step(0, 0.0, {"plant/state": {"z_w": np.zeros(1)}})


def test_the_model_runs_its_driver_and_publishes_every_arm(car):
    W = car.static_tyre_load()
    loads = {}
    for _ in range(150):  # 0.3 s at 2 ms: braking has begun at 0.2 s
        car.substep(0.002, W, np.zeros(4))
        loads = car.loads()
    assert set(loads) == {"arm", "arm_FL", "arm_FR", "arm_RL", "arm_RR"}
    assert loads["arm"] == loads["arm_FL"]
    for c in ("FL", "FR", "RL", "RR"):
        assert set(loads[f"arm_{c}"]) == {f.name for f in
                                          schema.BY_NAME[f"plant/arm_{c}"].fields}
    assert car._T_wheel[0] < 0.0 and car._T_wheel[0] / car._T_wheel[2] == pytest.approx(
        0.72 / 0.28)


@pytest.mark.parametrize("driver, match", [
    ({"steer": [[0.0, 0.0]]}, "speed"),
    ({"speed": [[0.0]]}, r"\[t, value\]"),
    ({"speed": [[0.0, 10.0]], "brake_balance": 1.5}, "brake_balance"),
    ({"speed": [[0.0, 10.0]], "wheel": 1}, "wheel"),
])
def test_a_bad_driver_table_is_refused_naming_the_key(driver, match):
    with pytest.raises(ScenarioError, match=match):
        build_plant_model({"model": "full_vehicle_double_wishbone", "driver": driver})
