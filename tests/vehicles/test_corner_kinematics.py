"""The corner linkage's curves (nodes/plant/corner_kinematics.py) against closed forms and
hand calculations, and against the PyBullet corner built from the same file."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from cosim import corner as cf
from nodes.plant import corner_kinematics as ck
from nodes.plant.model import GRAVITY

WIDE = Path(__file__).with_name("corners") / "wide_track.toml"
L, A, S, Y_BJ, Z_L, Z_U = 0.30, 0.18, 0.20, -0.05, -0.12, 0.20
"""Parallelogram corner: arm lever L, damper seat lever A, spring seat lever S [m]; ball
joints at y = Y_BJ, lower and upper arm heights Z_L, Z_U [m]."""


def parallelogram(k_theta_deg: float = 40.0, k_coil: float = 0.0) -> cf.Corner:
    """Equal, parallel arms, pivots straight inboard of the ball joints, a tie rod parallel
    and equal to the arms, vertical damper and spring: the upright translates."""
    yp = Y_BJ - L
    hp = {
        "lower_bush_front": [0.13, yp, Z_L], "lower_bush_rear": [-0.13, yp, Z_L],
        "lower_ball_joint": [0.0, Y_BJ, Z_L],
        "upper_bush_front": [0.13, yp, Z_U], "upper_bush_rear": [-0.13, yp, Z_U],
        "upper_ball_joint": [0.0, Y_BJ, Z_U],
        "tie_rod_inner": [-0.14, yp, -0.03], "tie_rod_outer": [-0.14, Y_BJ, -0.03],
        "damper_lower": [0.06, yp + A, Z_L], "damper_upper": [0.06, yp + A, 0.40],
        "spring_lower": [-0.06, yp + S, Z_L], "spring_upper": [-0.06, yp + S, 0.40],
    }
    spring = {"torsion_bar_nm_per_deg": k_theta_deg}
    if k_coil:
        spring["coil_n_per_m"] = k_coil
    k = 4.0e6
    return cf.from_dict({
        "format": "suscosim-corner", "version": 1, "name": "parallelogram",
        "frame": {"reference": "wheel_centre", "half_track": 0.7, "tyre_loaded_radius": 0.30},
        "hardpoints": hp, "masses": {"body": 500.0, "hub": 40.0, "lower_arm": 5.0,
                                     "upper_arm": 2.0, "tie_rod": 2.0},
        "spring": spring, "damper": {"c_nominal": 3000.0},
        "bushes": {n: {"radial": k, "axial": 1e6} for n in cf.BUSHES}})


def test_parallel_equal_arms_keep_camber_and_toe_zero():
    cv = ck.curves(parallelogram(), np.linspace(-0.08, 0.08, 9))
    assert np.abs(cv["camber"]).max() < 1e-9
    assert np.abs(cv["toe"]).max() < 1e-9
    # the upright translates on the arms' circle: z_w = L sin(theta)
    assert np.allclose(cv["z_w"], L * np.sin(cv["theta"]), atol=1e-12)


def test_damper_motion_ratio_is_the_lever_ratio():
    cv = ck.curves(parallelogram(), np.array([0.0, 0.05]))
    assert cv["mr_damper"][0] == pytest.approx(A / L, rel=1e-7)
    # away from ride height the vertical damper sees the seat's vertical speed only, and it
    # leans: MR = (A cos(theta) cos(beta) + A sin(theta) sin(beta)) / (L cos(theta)) with
    # beta its lean; hand calculation from the seat's position
    t = cv["theta"][1]
    seat = np.array([A * math.cos(t), A * math.sin(t)])
    top = np.array([A, 0.40 - Z_L])
    u = (top - seat) / np.linalg.norm(top - seat)
    v_seat = A * np.array([-math.sin(t), math.cos(t)])
    assert cv["mr_damper"][1] == pytest.approx(float(u @ v_seat) / (L * math.cos(t)), rel=1e-6)


def test_wheel_rate_is_torsion_bar_plus_coil_times_mr_squared():
    K = 40.0 * 180.0 / math.pi
    cv = ck.curves(parallelogram(40.0, 20000.0), np.array([0.0]))
    assert cv["wheel_rate_elastic"][0] == pytest.approx(K / L ** 2 + 20000.0 * (S / L) ** 2,
                                                        rel=1e-6)
    cv = ck.curves(parallelogram(40.0), np.array([0.0]))
    # torsion bar alone: z'' = 0 at ride height, so the preload adds nothing there
    assert cv["wheel_rate"][0] == pytest.approx(K / L ** 2, rel=1e-5)


def test_wheel_load_follows_the_torsion_bar_through_the_lever():
    K = 40.0 * 180.0 / math.pi
    W = 500.0 * GRAVITY
    z = np.array([-0.06, 0.0, 0.05])
    cv = ck.curves(parallelogram(40.0), z)
    t = np.arcsin(z / L)
    assert np.allclose(cv["wheel_load"], (W * L + K * t) / (L * np.cos(t)), rtol=1e-7)


def test_the_coil_carries_the_static_load_when_fitted():
    cv = ck.curves(parallelogram(40.0, 20000.0), np.array([0.0]))
    assert cv["wheel_load"][0] == pytest.approx(500.0 * GRAVITY, rel=1e-9)


def test_builtin_camber_gain_is_one_over_the_front_view_swing_arm():
    c = cf.builtin()
    P = {k: v[1:] for k, v in c.points.items()}  # front view (y, z): pivot axes along x
    a1, b1 = P["lower_bush_front"], P["lower_ball_joint"]
    a2, b2 = P["upper_bush_front"], P["upper_ball_joint"]
    # instant centre: where the two arm lines meet
    M = np.column_stack([b1 - a1, -(b2 - a2)])
    s = np.linalg.solve(M, a2 - a1)[0]
    ic = a1 + s * (b1 - a1)
    fvsa = -ic[0]  # wheel centre at y = 0
    assert fvsa == pytest.approx(4.06, abs=0.01)  # the geometry module's hand number
    cv = ck.curves(c, np.array([-0.002, 0.002]))
    gain = (cv["camber"][1] - cv["camber"][0]) / 0.004
    assert gain == pytest.approx(-1.0 / fvsa, rel=0.01)  # top inward in jounce


def test_equivalent_quarter_car_damper_is_c_mr_squared():
    c = cf.builtin()
    eq = ck.equivalent_quarter_car(c)
    assert eq["c_s"] == pytest.approx(3800.0 * eq["mr_damper"] ** 2, rel=1e-12)
    # hand number of the geometry module: MR = 0.185 cos(4.0 deg) / 0.2984
    lean = math.atan2(0.206 - 0.169, 0.40 + 0.13)
    assert eq["mr_damper"] == pytest.approx(0.185 * math.cos(lean) / 0.2984, rel=2e-3)
    assert eq["m_u"] == 47.75 and eq["m_s"] == 535.0  # Table 4.3


def test_lateral_compliance_hand_calculation():
    k = 4.0e6
    lc = ck.lateral_compliance(parallelogram())
    F_u = lc["ball_joint_share_upper"]
    # the ball-joint forces balance the 1 N at the contact patch and its moment
    assert F_u + (1.0 - F_u) == 1.0
    assert F_u * Z_U + (1.0 - F_u) * Z_L == pytest.approx(-0.30, abs=1e-12)
    # ball joints midway between equal bushes: each arm moves by its force / (2 k)
    y_l, y_u = (1.0 - F_u) / (2 * k), F_u / (2 * k)
    gamma = (y_u - y_l) / (Z_U - Z_L)
    assert lc["camber_compliance"] == pytest.approx(gamma, rel=1e-12)
    assert lc["lateral_stiffness_wc"] == pytest.approx(1.0 / (y_l - gamma * Z_L), rel=1e-12)


def test_a_travel_the_arms_cannot_reach_is_refused():
    # 0.35 m of jounce: more than the lower arm's 0.30 m lever can lift the wheel
    with pytest.raises(ValueError, match="does not close"):
        ck.curves(cf.builtin(), np.array([0.35]))


def _pybullet_static_travel(corner: cf.Corner, dF: float = 400.0) -> dict[float, float]:
    """The PyBullet corner with the body held: the wheel travel [m] under -dF and +dF of
    tyre load from static [N]."""
    from nodes.plant.double_wishbone import BODY, DoubleWishboneCorner
    from nodes.plant.quiet_pybullet import p

    m = DoubleWishboneCorner(corner=corner)
    try:
        c, b = m.client, m.body
        p.setJointMotorControl2(b, BODY, p.POSITION_CONTROL,
                                targetPosition=p.getJointState(b, BODY, physicsClientId=c)[0],
                                force=1e9, positionGain=1.0, velocityGain=1.0,
                                physicsClientId=c)
        sid = p.saveState(physicsClientId=c)
        W = m.static_tyre_load()
        z = {}
        for f in (-dF, dF):
            p.restoreState(sid, physicsClientId=c)
            m._read()
            for _ in range(3000):  # over-damped: settles well inside 3 s
                m.substep(1e-3, W + f, np.array([6000.0 * m.state()["v_damper"][0]]))
            st = m.state()
            z[f] = float(st["z_w"][0] - st["z_b"][0])
    finally:
        m.close()
    return z


@pytest.mark.parametrize("which", ["builtin", "wide_track"])
def test_wheel_rate_is_the_pybullet_corners_static_rate(which):
    corner = cf.builtin() if which == "builtin" else cf.load(WIDE)
    z = _pybullet_static_travel(corner)
    assert z[400.0] > 0.01 and z[-400.0] < -0.01  # ~13 mm either way
    cv = ck.curves(corner, np.array([z[-400.0], z[400.0]]))
    # the linkage's wheel load between the two travels the PyBullet corner settled at under
    # 800 N more tyre load (the body held: all of it goes through the spring)
    assert cv["wheel_load"][1] - cv["wheel_load"][0] == pytest.approx(800.0, rel=5e-3)
