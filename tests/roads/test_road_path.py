"""The road under a cornering vehicle (issue #44 item 3): a 1-D profile laid along the path the
driver follows, read at each wheel's station (arc length), not at its world x."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cosim import plaindata
from cosim import scenario as sc
from nodes.tyre_road.node import TyreRoad
from nodes.tyre_road.roads import SampledRoad
from nodes.tyre_road.wheel_paths import RoadPath, road_heights_at

ROOT = Path(__file__).resolve().parents[2]
PAVE = ROOT / "scenarios" / "events" / "cornering_pave.toml"


@pytest.mark.parametrize("R", [40.0, -25.0])
def test_a_point_on_the_circle_is_at_its_arc_length_past_a_lap(R: float) -> None:
    x0, y0 = 2.0, -1.0
    path = RoadPath((x0, y0), R)
    arc = np.linspace(-3.0, 2.3 * np.pi * abs(R), 400)  # behind the start, then > 1 lap
    u = None
    got = []
    for s in arc:
        p = s / R
        x, y = x0 + R * np.sin(p), y0 + R * (1 - np.cos(p))
        # and a point 0.7 m to the left of the line (a left wheel) at the same station
        xl, yl = x - 0.7 * np.sin(p), y + 0.7 * np.cos(p)
        u = path.station(np.array([x, xl]), np.array([y, yl]), u)
        got.append(u)
    got_a = np.array(got)
    np.testing.assert_allclose(got_a[:, 0], arc, atol=1e-9)
    np.testing.assert_allclose(got_a[:, 1], arc, atol=1e-9)


def test_straight_path_is_the_world_x() -> None:
    path = RoadPath((1.5, 0.3))
    np.testing.assert_allclose(path.station(np.array([1.5, 4.0]), np.array([9.0, -3.0])),
                               [0.0, 2.5])


def test_a_wheel_on_a_circle_sees_the_profile_at_its_arc_length() -> None:
    R = 40.0
    s_prof = np.linspace(0.0, 60.0, 6001)
    road = SampledRoad(x=s_prof, z_left=0.01 * np.sin(2 * np.pi * s_prof / 0.9),
                       z_right=0.01 * np.sin(2 * np.pi * s_prof / 0.9 + 1.0), speed=14.0)
    path = RoadPath((0.0, 0.0), R)
    arc = np.linspace(0.0, 55.0, 300)
    x, y = R * np.sin(arc / R), R * (1 - np.cos(arc / R))
    u = None
    z = []
    for xi, yi in zip(x, y, strict=True):
        u = path.station(np.array([xi]), np.array([yi]), u)
        z.append(road_heights_at(road, u, [1])[0, 0])
    np.testing.assert_allclose(z, road.height(arc, 1), atol=1e-12)
    # the world x is 55 m * (1 - sinc) short of the arc at the end: another profile
    assert np.abs(np.array(z) - road.height(x, 1)).max() > 0.005


def test_the_node_reads_cornering_pave_along_the_arc() -> None:
    """The tyre/road node of scenarios/events/cornering_pave.toml, fed wheel centres that go
    round its driver's R = 40 m circle: z_g is the pave at each wheel's station."""
    scenario = sc.load(PAVE)
    R = float(scenario["vehicle"]["driver"]["radius"])
    half_t, L, v = 0.7055, 2.9, 14.0
    info = {"static_tyre_load": [5000.0] * 4, "wheel_x": [0.0, 0.0, -L, -L],
            "wheel_track": [0, 1, 0, 1], "corner_names": ["FL", "FR", "RL", "RR"]}
    node = TyreRoad(scenario, {"info": {"plant": info}})
    side = np.array([half_t, -half_t, half_t, -half_t])  # left of the line +
    lag = np.array([0.0, 0.0, L, L])  # the rear axle's centre, L behind on the circle
    for k in range(0, 1500, 7):
        s = v * k * 0.002
        phi = (s - lag) / R
        r = R - side
        x, y = 5.0 + r * np.sin(phi), 0.2 + R - r * np.cos(phi)
        st = {"x_wc": x, "y_wc": y, "vx_wc": np.full(4, v), "vy_wc": np.zeros(4),
              "omega_w": np.full(4, v / 0.3), "gamma": np.zeros(4), "r_l": np.full(4, 0.3),
              "z_w": np.zeros(4)}
        out = node.step(k, k * 0.002, {"plant/state": st})
        want = [node.road.height(np.array([s - lag[i]]), tr)[0] if s - lag[i] >= 0 else 0.0
                for i, tr in enumerate((0, 1, 0, 1))]
        np.testing.assert_allclose(out["z_g"], want, atol=1e-12)
    assert s > 40.0  # the world x, R sin(s / R), is 6.3 m short of the arc by then
    # its state (the path's origin, the last stations) is plain data for a checkpoint
    state = plaindata.decode(plaindata.encode(node.checkpoint_state()))
    assert state["_origin"] == pytest.approx((5.0, 0.2))
    np.testing.assert_array_equal(state["_u"], node._u)
