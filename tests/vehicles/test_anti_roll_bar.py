"""The four-corner vehicle's anti-roll bars (nodes/plant/anti_roll_bar.py) and the cornering on
the pave they make possible (#31): the bar's torques against its definition, and 0.5 g on the
Ch 6 pave without rolling over (scenarios/events/cornering_pave.toml run by the one-process
engine, as tests/vehicles/test_full_vehicle_events.py runs its events: the wheels read the road
at their stations along the driver's circle, where a one-process loop before read it at their
world x; late mean roll 0.052 rad, 87 % of wheel steps loaded, against 0.048 rad and 91 %)."""

from __future__ import annotations

import numpy as np
import pytest

from cosim import corner as corner_file
from nodes.plant.anti_roll_bar import AntiRollBar, axle_bars, axle_torques, wheel_lever
from nodes.plant.full_vehicle_dw import FullVehicleDoubleWishbone, FullVehicleDWParams
from nodes.plant.model import GRAVITY
from tests.conftest import ROOT

from ._sim import event_run

PAVE = ROOT / "scenarios" / "events" / "cornering_pave.toml"


def test_the_bar_resists_roll_only_with_its_roll_stiffness_at_the_wheels():
    bar = AntiRollBar(roll_stiffness=60000.0, track=1.4, lever=0.3)
    # heave and pitch (both arms alike): no torque
    assert bar.torques(0.05, 0.05) == (0.0, 0.0)
    # the body rolled by phi over wheels on the ground: the arms by -+ t phi / (2 l)
    phi = 0.02
    aL, aR = -1.4 * phi / (2 * 0.3), 1.4 * phi / (2 * 0.3)
    tL, tR = bar.torques(aL, aR)
    assert tL == -tR and tL > 0  # the arm in rebound (left) turned toward jounce: resists roll
    # as vertical forces at the wheel centres (torque / lever), their roll moment is K phi
    moment = (tL / 0.3 - tR / 0.3) * 1.4 / 2
    assert moment == pytest.approx(60000.0 * phi, rel=1e-12)
    # per axle, FL/FR and RL/RR; an axle without a bar gets none
    out = axle_torques((bar, None), np.array([aL, aR, aL, aR]))
    assert out[:2] == pytest.approx([tL, tR]) and list(out[2:]) == [0.0, 0.0]
    with pytest.raises(ValueError, match="track"):
        AntiRollBar(1.0, 0.0, 0.3)


def test_the_built_in_bars_and_switching_them_off():
    c = corner_file.builtin()
    # the corner's wheel-centre lever: 0.2984 m (nodes/plant/double_wishbone_geometry.py)
    assert wheel_lever(c) == pytest.approx(0.2984, abs=2e-4)
    f, r = axle_bars(c, c, True, 1200.0, 500.0)
    assert f is not None and r is not None
    assert f.roll_stiffness == pytest.approx(1200.0 * 180 / np.pi)
    assert f.track == pytest.approx(1.411)
    assert axle_bars(c, c, False, 1200.0, 500.0) == (None, None)
    assert FullVehicleDWParams().anti_roll_bars  # on for the four-corner vehicle


@pytest.fixture(scope="module")
def pave_cornering(tmp_path_factory):
    """R = 40 m at sqrt(0.5 g R) on the pave, 2.5 s."""
    return event_run(PAVE, tmp_path_factory.mktemp("pave"), "run.t_end=2.5")


def test_cornering_on_the_pave_does_not_roll_over(pave_cornering):
    hist = pave_cornering
    assert hist.t[-1] == pytest.approx(2.5)
    assert np.all(np.isfinite(hist.roll)) and np.all(np.isfinite(hist.F_z))
    # bounded: the run without bars and with independent long waves rolled 0.27 rad by 1.2 s
    # and over (1.1 rad at 3 s); here the body rolls about the flat road's 0.049 rad
    assert float(np.max(np.abs(hist.roll))) < 0.12
    late = hist.t >= 1.5
    assert float(np.mean(np.abs(hist.roll[late]))) == pytest.approx(0.049, rel=0.3)
    # it still corners: the driver's 0.5 g on the setts
    assert float(np.mean(hist.a_y[late])) == pytest.approx(0.5 * GRAVITY, rel=0.15)
    # and the wheels stay on the road most of the time (the setts make them hop)
    assert float(np.mean(hist.F_z[late] > 0.0)) > 0.8


@pytest.mark.parametrize("bars, moment, front, rear", [
    (True, 5000.0, 29453.0 + 2 * 1200.0 * 180 / np.pi / 1.411 ** 2,  # k_w + 2 K_bar / t^2
     29453.0 + 2 * 500.0 * 180 / np.pi / 1.411 ** 2),
    (False, 2000.0, 29453.0, 29453.0),  # the corner check's wheel rate alone [N/m]
])
def test_a_roll_moment_meets_the_wheel_rate_plus_the_bar_s(bars, moment, front, rear):
    """The parked car under a steady roll moment on the body (no lateral tyre force): each
    wheel's load change over its travel relative to the body is the corner's wheel rate plus
    the bar's 2 K_bar / t^2 (its roll stiffness K_bar = k_bar,w t^2 / 2 at the wheels). The
    moments give 22-26 and 27 mm of travel. Measured: 98.3 / 58.3 kN/m with the bars
    (hand 98.5 / 58.2), 29.2 / 29.4 kN/m without (hand 29.45)."""
    from nodes.plant.quiet_pybullet import p

    car = FullVehicleDoubleWishbone(FullVehicleDWParams(anti_roll_bars=bars))
    try:
        apply = car._apply

        def with_moment() -> None:
            apply()
            p.applyExternalTorque(car.body, -1, [moment, 0.0, 0.0], p.WORLD_FRAME,
                                  physicsClientId=car.client)

        car._apply = with_moment  # type: ignore[method-assign]
        W = car.static_tyre_load()
        for _ in range(3000):  # 3 s at 1 ms, a heavy damper: settled within 1 %
            st = car.state()
            F = np.maximum(0.0, W - 239000.0 * st["z_w"])
            car.substep(0.001, F, 8000.0 * st["v_damper"])
        st = car.state()
        rate = np.abs((F - W) / (st["z_w"] - st["z_b"]))
    finally:
        car.close()
    assert np.mean(rate[:2]) == pytest.approx(front, rel=0.03)
    assert np.mean(rate[2:]) == pytest.approx(rear, rel=0.03)
