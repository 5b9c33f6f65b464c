"""MR damper of Table 5.1: forces against numbers worked out by hand from the polynomials,
continuity of the bi-viscous law, steady state of the dynamic model, and passivity."""

from __future__ import annotations

import numpy as np
import pytest

from cosim.errors import ScenarioError
from nodes.controller.mr_damper import (
    MRDamper,
    MRParams,
    bi_viscous_force,
    c_post,
    knee,
    yield_force,
)

# Hand evaluation of Table 5.1 (written out, not computed with the module's polynomials):
# I = 0.3 A: c_post = -5257.3*0.09 + 7671.5*0.3 + 3203.3 = -473.157 + 2301.45 + 3203.3
#            F_y = -13417*0.0081 + 25233*0.027 - 17787*0.09 + 6145.8*0.3 + 1.33
#                = -108.6777 + 681.291 - 1600.83 + 1843.74 + 1.33
# I = 0.6 A: c_post = -5257.3*0.36 + 7671.5*0.6 + 3203.3 = -1892.628 + 4602.9 + 3203.3
#            F_y = -13417*0.1296 + 25233*0.216 - 17787*0.36 + 6145.8*0.6 + 1.33
#                = -1738.8432 + 5450.328 - 6403.32 + 3687.48 + 1.33
C_POST = {0.0: 3203.3, 0.3: 5031.593, 0.6: 5913.572}
F_Y = {0.0: 1.33, 0.3: 816.8533, 0.6: 996.9748}


@pytest.mark.parametrize("I", [0.0, 0.3, 0.6])
def test_polynomials_match_hand_values(I):
    assert c_post(I) == pytest.approx(C_POST[I], rel=1e-9)
    assert yield_force(I) == pytest.approx(F_Y[I], rel=1e-9)


@pytest.mark.parametrize(
    ("I", "v", "F"),
    [
        (0.0, 0.1, 1.33 + 320.33),  # 321.66 N
        (0.0, 0.5, 1.33 + 1601.65),
        (0.3, 0.5, 816.8533 + 0.5 * 5031.593),  # 3332.65 N
        (0.6, 0.5, 996.9748 + 0.5 * 5913.572),  # 3953.76 N (derived table: 3954)
        (0.6, -0.1, -(996.9748 + 591.3572)),  # rebound: odd in v
        (0.6, 0.01, 557.6),  # pre-yield: v_y(0.6) = 996.9748 / (55760 - 5913.572) = 0.0200
    ],
)
def test_static_force_at_table_points(I, v, F):
    assert bi_viscous_force(v, I) == pytest.approx(F, rel=1e-6)


def test_bi_viscous_is_continuous_at_the_knee_and_monotonic_in_current():
    for I in (0.1, 0.3, 0.6):
        vy = float(knee(I)[2])
        below = bi_viscous_force(vy * (1 - 1e-9), I)
        above = bi_viscous_force(vy * (1 + 1e-9), I)
        assert above == pytest.approx(below, rel=1e-6)
        assert bi_viscous_force(0.0, I) == 0.0
    v = np.linspace(-1.0, 1.0, 41)
    F = np.array([bi_viscous_force(v, I) for I in np.linspace(0.0, 0.6, 13)])
    assert np.all(np.diff(np.abs(F), axis=0) >= -1e-9)


def test_dynamic_model_settles_to_the_static_force():
    d = MRDamper(2, MRParams())
    d.start(np.zeros(2), np.zeros(2))
    I = np.array([0.0, 0.6])
    v = np.array([0.3, -0.3])
    F = d.advance(v, v, 0.2, lambda frac, F_now: I)  # 0.2 s >> c_post/K_f ~ 4 ms
    np.testing.assert_allclose(F, [1.33 + 0.3 * 3203.3, -(996.9748 + 0.3 * 5913.572)], rtol=1e-4)


def test_motion_ratio_scales_velocity_and_force():
    d = MRDamper(1, MRParams(motion_ratio=0.5, dynamics=False))
    # damper sees 0.5 * 0.4 = 0.2 m/s; wheel sees 0.5 * F
    assert float(d.static_force(0.4, 0.0)) == pytest.approx(0.5 * (1.33 + 0.2 * 3203.3))
    assert float(d.c_eff(0.0)) == pytest.approx(0.25 * 3203.3)


def test_mr_damper_never_gives_out_more_energy_than_it_took():
    # Random stroke velocities and currents switched every step: the work done on the damper
    # from rest, sum of F v dt, stays >= 0 (no energy input from a semi-active device).
    rng = np.random.default_rng(7)
    p = MRParams(substep=5e-4)
    d = MRDamper(3, p)
    d.start(np.zeros(3), np.zeros(3))
    dt = 5e-4
    W = np.zeros(3)
    v = np.zeros(3)
    for _ in range(4000):
        v = np.clip(v + rng.normal(0.0, 0.05, 3), -1.0, 1.0)
        I = rng.choice([0.0, 0.6], 3)
        F = d.advance(v, v, dt, lambda frac, F_now, I=I: I)
        W += F * v * dt
        assert np.all(W >= -1e-9)
    stored = 0.5 * p.K_f * d.s**2 + 0.5 * p.M_f * d.v_f**2
    assert np.all(W >= stored - 1e-9)


def test_damper_overrides_are_validated():
    p = MRParams.from_config({"K_f": 2.0e6, "dynamics": False}, "controller.damper")
    assert p.K_f == 2.0e6 and not p.dynamics and p.c_pre == 55760.0
    with pytest.raises(ScenarioError) as err:
        MRParams.from_config({"I_max": 1.0}, "controller.damper")
    assert err.value.key == "controller.damper.I_max"
    with pytest.raises(ScenarioError) as err:
        MRParams.from_config({"Kf": 1.0}, "controller.damper")
    assert err.value.key == "controller.damper.Kf"
