"""Jounce bumper: the force law against its closed form, first contact on the PyBullet corner
against an independent front-view four-bar solution, the force on the arm over a big bump,
the scenario keys. (The arm's balance with its inertia while the bumper pushes on it:
test_double_wishbone.py.)"""

import numpy as np
import pytest

from cosim import lower_arm as la
from cosim.errors import ScenarioError
from nodes.plant import double_wishbone as dw
from nodes.plant import double_wishbone_geometry as geo
from nodes.plant.bump_stop import BumpStopParams, bump_stop_force
from nodes.plant.models import build_plant_model

from ._sim import big_bump_run

BS = BumpStopParams()


def bump_stop_rate(d: float) -> float:
    """The closed-form rate dF/d(delta) [N/m] of the default bumper (the module docstring's
    law): 0 while free, k_0 / (1 - delta/s_b)^2, k_0 / (1 - r)^2 beyond r s_b (an oracle)."""
    if d <= 0.0:
        return 0.0
    return BS.initial_rate / (1.0 - min(d / BS.stroke, BS.transition)) ** 2


# ------------------------------------------------------------------ the force law
def test_free_until_the_clearance_closes():
    for d in (-0.05, -1e-9, 0.0):
        assert bump_stop_force(d) == 0.0 and bump_stop_rate(d) == 0.0
    assert bump_stop_force(1e-6) == pytest.approx(BS.initial_rate * 1e-6, rel=1e-4)


def test_closed_form_points():
    k0, sb = BS.initial_rate, BS.stroke
    # hyperbola k0 d / (1 - d/sb): at half the block compression F = k0 sb exactly
    assert bump_stop_force(sb / 2) == pytest.approx(k0 * sb, rel=1e-12)
    assert bump_stop_rate(sb / 2) == pytest.approx(4 * k0, rel=1e-12)
    # the numbers the module docstring quotes (default bumper)
    assert bump_stop_force(0.015) == pytest.approx(1920.0, rel=1e-9)
    assert bump_stop_force(0.020) == pytest.approx(3200.0, rel=1e-9)
    assert 2000 < bump_stop_force(0.018) < 3000          # "a few kN at 15-20 mm"
    assert bump_stop_force(0.034) > 15000.0               # "above 15 kN near full compression"
    assert bump_stop_force(0.036) == pytest.approx(28800.0, rel=1e-9)


def test_continuous_monotonic_and_its_derivative():
    d = np.linspace(1e-5, 0.06, 6001)  # past the block: the tangent continuation
    F = np.array([bump_stop_force(x) for x in d])
    k = np.array([bump_stop_rate(x) for x in d])
    assert np.all(np.diff(F) > 0) and np.all(np.diff(k) >= 0)
    h = 1e-8
    fd = np.array([(bump_stop_force(x + h) - bump_stop_force(x - h)) / (2 * h) for x in d])
    assert np.allclose(fd, k, rtol=1e-5)
    d_t = BS.transition * BS.stroke  # C1 at the switch to the tangent
    assert bump_stop_force(d_t + 1e-9) == pytest.approx(bump_stop_force(d_t), abs=0.01)
    assert bump_stop_rate(d_t + 1e-9) == pytest.approx(100 * BS.initial_rate)


def test_bad_parameters():
    with pytest.raises(ValueError):
        BumpStopParams(clearance=0.0)
    with pytest.raises(ValueError):
        BumpStopParams(transition=1.0)


# ------------------------------------------------------------------ on the corner
def _rot(a: float) -> np.ndarray:
    return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])


def four_bar_wheel_rise(theta: float) -> float:
    """Rise of the wheel centre relative to the body [m] at lower-arm angle theta [rad], from
    the front-view (y, z) four-bar: both arms turn about x, so their ball joints move in y-z
    planes and the front-view distance between them is constant. The upright's steer is
    ignored."""
    g = geo.BUILTIN
    A = 0.5 * (g.lower_bush_front + g.lower_bush_rear)[1:]
    C = 0.5 * (g.upper_bush_front + g.upper_bush_rear)[1:]
    B0, D0, W0 = g.lower_ball_joint[1:], g.upper_ball_joint[1:], g.wheel_centre[1:]
    B = A + _rot(theta) @ (B0 - A)
    r1, r2 = np.linalg.norm(D0 - C), np.linalg.norm(D0 - B0)
    d = np.linalg.norm(B - C)
    a = (r1 ** 2 - r2 ** 2 + d ** 2) / (2 * d)
    h = np.sqrt(r1 ** 2 - a ** 2)
    mid, n = C + a * (B - C) / d, np.array([C[1] - B[1], B[0] - C[0]]) / d
    D = min((mid + h * n, mid - h * n), key=lambda q: np.linalg.norm(q - D0))
    phi = np.arctan2(*(D - B)[::-1]) - np.arctan2(*(D0 - B0)[::-1])
    return float((B + _rot(phi) @ (W0 - B0))[1] - W0[1])


def test_no_contact_at_static_ride_height():
    m = dw.DoubleWishboneCorner()
    try:
        W = m.static_tyre_load()
        assert m.bump_stop_compression() == pytest.approx(-BS.clearance, abs=1e-9)
        for _ in range(500):
            m.substep(1e-3, W, np.zeros(1))
            assert m.extra_response()["F_bs"][0] == 0.0
        L = m.loads()["arm"]
        assert L["bump_stop_y"] == 0.0 and L["bump_stop_z"] == 0.0
    finally:
        m.close()


def test_first_contact_travel_matches_the_geometry():
    """Pull the suspension into jounce slowly (a damper-axis tension ramp, heavily damped):
    the bumper first touches at the arm angle asin(g / 0.215) and at the wheel travel the
    four-bar gives (58.5 mm from static ride height), and its force then follows the
    characteristic at the pad's rise 0.215 sin(theta) - g."""
    m = dw.DoubleWishboneCorner()
    W = m.static_tyre_load()
    rows = []
    try:
        for k in range(4000):
            st = m.state()
            F_t = np.maximum(0.0, W - 239000.0 * st["z_w"])
            F_bs = float(m.extra_response()["F_bs"][0])
            rows.append((float(st["z_w"][0] - st["z_b"][0]), float(st["arm_angle"][0]), F_bs))
            m.substep(1e-3, F_t, 30000.0 * st["v_damper"] - 2.0 * k)  # tension: -2 kN/s
    finally:
        m.close()
    rel, theta, F = np.array(rows).T
    i = int(np.argmax(F > 0))
    assert i > 0 and F[:i].max() == 0.0
    pad_lever = la.BUMP_STOP_PAD[1]
    theta_c = np.arcsin(BS.clearance / pad_lever)
    assert theta[i - 1] <= theta_c <= theta[i]
    s_c = four_bar_wheel_rise(theta_c)
    assert s_c == pytest.approx(0.0585, abs=5e-4)   # about 58 mm of wheel jounce
    assert rel[i - 1] <= s_c + 2e-4 and rel[i] >= s_c - 2e-4
    # in contact, F_bs = F(0.215 sin(theta) - g) (the pad rides on the arm, turning about x)
    j = int(np.argmax(F))
    assert F[j] > 2500.0
    assert F[j] == pytest.approx(bump_stop_force(pad_lever * np.sin(theta[j]) - BS.clearance),
                                 rel=1e-6)


def test_big_bump_hits_the_bumper_and_the_arm_sees_it(big_bump):
    recs, _ = big_bump
    F = np.array([r["F_bs"] for r in recs])
    bz = np.array([r["L"]["bump_stop_z"] for r in recs])
    by = np.array([r["L"]["bump_stop_y"] for r in recs])
    th = np.array([r["theta"] for r in recs])
    assert F.max() > 3000.0 and np.all(F >= 0)
    assert (F > 0).sum() > 20  # several ms of contact
    # the force on the arm at the pad: (0, 0, -F_bs) turned into the arm frame
    assert np.allclose(bz, -F * np.cos(th), rtol=1e-6, atol=1e-6)
    assert np.allclose(by, -F * np.sin(th), rtol=1e-6, atol=1e-6)
    assert np.all(bz <= 0.0)
    # contact only beyond the clearance's wheel travel
    rel = np.array([r["rel"] for r in recs])
    assert rel[F > 0].min() >= 0.058


def test_without_the_bumper_nothing_pushes_and_the_travel_is_larger(big_bump):
    recs, _ = big_bump
    free, _ = big_bump_run(False, dt=1e-3)
    assert all(r["F_bs"] == 0.0 and r["L"]["bump_stop_z"] == 0.0 for r in free)
    assert max(r["rel"] for r in free) > max(r["rel"] for r in recs) + 0.005


@pytest.mark.parametrize("cfg,key", [
    ({"bump_stop": "yes"}, "vehicle.bump_stop"),
    ({"bump_stop": 1}, "vehicle.bump_stop"),
    ({"bump_stop_clearance": -0.01}, "vehicle.bump_stop_clearance"),
    ({"bump_stop_initial_rate": "soft"}, "vehicle.bump_stop_initial_rate"),
    ({"bump_stop_stroke": 0}, "vehicle.bump_stop_stroke"),
])
def test_bad_bump_stop_config_names_the_key(cfg, key):
    with pytest.raises(ScenarioError) as e:
        build_plant_model({"model": "quarter_car_double_wishbone", **cfg})
    assert e.value.key == key


def test_bump_stop_from_the_vehicle_section():
    m = build_plant_model({"model": "quarter_car_double_wishbone", "bump_stop": False})
    try:
        assert m.bump_stop is None and m.info()["bump_stop"] is None
    finally:
        m.close()
    m = build_plant_model({"model": "quarter_car_double_wishbone",
                           "bump_stop_clearance": 0.03})
    try:
        assert m.bump_stop.clearance == 0.03
        assert m.info()["bump_stop"]["clearance_m"] == 0.03
    finally:
        m.close()


def test_passive_ch4_bump_pothole_stays_clear_and_soft_damping_touches():
    """Thesis: the passive Ch. 4 validation on the bump + pothole did not engage the bump stop;
    the semi-active runs of Ch. 5 (soft damping states) hit it on the bump."""
    from nodes.plant.bump_stop_study import road_run
    from nodes.plant.equivalent_lumped import SPEED, ch4_bump_pothole

    def road(t):
        return float(ch4_bump_pothole(SPEED * t))

    passive = road_run(road, 3800.0, t_end=1.2, dt=2e-3)
    soft = road_run(road, 1000.0, t_end=1.2, dt=2e-3)
    assert passive["F_bs_max"] == 0.0
    assert 0.045 < passive["jounce_max_m"] < 0.0585 - 0.003  # 3 mm or more to spare
    assert soft["F_bs_max"] > 0.0
