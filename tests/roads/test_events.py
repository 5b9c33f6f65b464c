"""Road events, the Road interface, wheel paths and build_road validation."""

import numpy as np
import pytest

from cosim.errors import ScenarioError
from nodes.tyre_road.config import build_road
from nodes.tyre_road.roads import bump_height, pothole_height, ramp_height, step_height
from nodes.tyre_road.wheel_paths import road_heights


def test_event_shapes():
    s = np.array([0.0, 0.99, 1.0, 1.5, 2.0, 3.0])
    assert np.allclose(step_height(s, 1.0, 0.02), [0, 0, 0.02, 0.02, 0.02, 0.02])
    assert np.allclose(ramp_height(s, 1.0, 0.1, 1.0), [0, 0, 0, 0.05, 0.1, 0.1])
    assert np.allclose(bump_height(s, 1.0, 0.04, 1.0), [0, 0, 0, 0.04, 0, 0], atol=1e-12)
    assert np.allclose(pothole_height(s, 1.0, 0.03, 1.0), [0, 0, 0, -0.03, 0, 0], atol=1e-12)
    assert np.allclose(pothole_height(s, 1.0, 0.03, 1.0, "rect"), [0, 0, -.03, -.03, 0, 0])


def test_t_start_uses_speed_and_duration():
    road = build_road({"type": "step", "speed_kmh": 36.0, "length_m": 40.0,
                       "height": 0.02, "t_start": 0.5})
    assert road.speed == pytest.approx(10.0)
    assert road.duration_s == pytest.approx(4.0)
    z = road.height(np.array([4.99, 5.0]), 0)
    assert np.allclose(z, [0.0, 0.02])


def test_events_list_and_tracks():
    road = build_road({"type": "events", "speed_kmh": 34.0, "length_m": 15.0, "events": [
        {"type": "bump", "height": 0.05, "x_start": 3.0, "length": 1.0},
        {"type": "pothole", "depth": 0.04, "x_start": 10.0, "length": 0.6, "tracks": "right"},
    ]})
    assert road.duration_s == pytest.approx(15.0 / (34 / 3.6))
    assert road.height(np.array([3.5]), 0)[0] == pytest.approx(0.05)
    assert road.height(np.array([10.3]), 1)[0] == pytest.approx(-0.04)
    assert road.height(np.array([10.3]), 0)[0] == 0.0


def test_rear_wheel_follows_front_after_wheelbase_over_speed():
    road = build_road({"type": "step", "speed_kmh": 36.0, "height": 0.02, "x_start": 1.0})
    wheel_x, tracks = [0.0, 0.0, -2.774, -2.774], [0, 1, 0, 1]
    t_front, t_rear = 0.1, 0.1 + 2.774 / 10.0
    z_front = road_heights(road, t_front + 1e-6, wheel_x, tracks)[:, 0]
    assert np.allclose(z_front, [0.02, 0.02, 0, 0])
    assert np.allclose(road_heights(road, t_rear - 1e-4, wheel_x, tracks)[:, 0],
                       [0.02, 0.02, 0, 0])
    assert np.allclose(road_heights(road, t_rear + 1e-4, wheel_x, tracks)[:, 0], 0.02)


def test_corners_restricts_excitation():
    road = build_road({"type": "step", "speed_kmh": 36.0, "height": 0.02, "x_start": 0.0,
                       "corners": ["FR"]})
    z = road_heights(road, 1.0, [0, 0, -2.7, -2.7], [0, 1, 0, 1],
                     corner_names=["FL", "FR", "RL", "RR"])[:, 0]
    assert np.allclose(z, [0, 0.02, 0, 0])


@pytest.mark.parametrize("cfg,key", [
    ({"type": "hill", "speed_kmh": 34}, "road.type"),
    ({"type": "step", "height": 0.02}, "road.speed_kmh"),
    ({"type": "step", "speed_kmh": -1, "height": 0.02}, "road.speed_kmh"),
    ({"type": "step", "speed_kmh": 34, "height": "big"}, "road.height"),
    ({"type": "bump", "speed_kmh": 34, "height": 0.02}, "road.length"),
    ({"type": "step", "speed_kmh": 34, "height": 0.02, "lenght": 3}, "road.lenght"),
    ({"type": "pothole", "speed_kmh": 34, "depth": -0.02, "length": 1}, "road.depth"),
    ({"type": "iso8608", "speed_kmh": 34, "length_m": 100, "class": "Z"}, "road.class"),
    ({"type": "iso8608", "speed_kmh": 34, "length_m": 100, "class": "C",
      "correlation": 2.0}, "road.correlation"),
    ({"type": "iso8608", "speed_kmh": 34, "class": "C"}, "road.length_m"),
    ({"type": "csv", "speed_kmh": 34}, "road.path"),
    ({"type": "events", "speed_kmh": 34, "events": [{"type": "step"}]},
     "road.events[0].height"),
    ({"type": "step", "speed_kmh": 34, "height": 0.02, "corners": ["XX"]}, "road.corners"),
])
def test_bad_road_config_names_the_key(cfg, key):
    with pytest.raises(ScenarioError) as e:
        build_road(cfg)
    assert e.value.key == key
