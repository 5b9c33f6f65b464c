"""The four-corner double-wishbone vehicle (nodes/plant/full_vehicle_dw.py, #31 item 2's
first piece): its static state, its mirror symmetry, and its body mode against the quarter
car its corner file's check gives."""

from __future__ import annotations

import numpy as np
import pytest

from cosim import corner as cf
from nodes.plant import corner_kinematics as ck
from nodes.plant.full_vehicle_dw import FullVehicleDoubleWishbone, FullVehicleDWParams
from nodes.plant.model import GRAVITY
from nodes.plant.models import build_plant_model

K_T = 239000.0
M, L, T = 4 * 535.0, 2.774, 1.411
# dynamic index 1 in pitch and roll, CG mid-wheelbase: every corner is a quarter car of M/4
DECOUPLED = FullVehicleDWParams(sprung_mass=M, cg_to_front_axle=L / 2, wheelbase=L,
                                pitch_inertia=M * (L / 2) ** 2, roll_inertia=M * (T / 2) ** 2,
                                yaw_inertia=M * ((L / 2) ** 2 + (T / 2) ** 2))


@pytest.fixture(scope="module")
def car():
    m = FullVehicleDoubleWishbone()
    yield m
    m.close()


def test_static_loads_carry_the_weight_and_balance_the_pitch_moment(car):
    W = car.static_tyre_load()
    unsprung = 4 * 47.75
    assert W.sum() == pytest.approx((1870.0 + unsprung) * GRAVITY, rel=1e-12)
    assert W[0] == W[1] and W[2] == W[3]
    # hand calculation with the unsprung mass at the wheel centres: the front axle carries
    # M g b / L + 2 m_u g (the arms' centres of mass sit a few mm off the axle lines)
    a = car.params.cg_to_front_axle
    front = 1870.0 * GRAVITY * (L - a) / L + 2 * 47.75 * GRAVITY
    assert W[0] + W[1] == pytest.approx(front, rel=2e-3)
    # the torsion preloads of mirrored corners are mirrored (the arm turns the other way)
    # (the front pair within 1e-5: the steering rack's motor joins the constraint solve and
    # its iterations leave 4.5e-6 of asymmetry between the two tie rods)
    assert car.tau0[1] == pytest.approx(-car.tau0[0], rel=1e-5)
    assert car.tau0[3] == pytest.approx(-car.tau0[2], rel=1e-6)


def test_it_stays_in_static_equilibrium(car):
    W = car.static_tyre_load()
    for _ in range(200):
        car.substep(1e-3, W, 3800.0 * car.state()["v_damper"])
    st = car.state()
    for key in ("z_b", "z_w", "z_damper", "heave", "pitch", "roll"):
        assert np.abs(st[key]).max() < 1e-6, key


def test_static_arm_loads_mirror_left_right_and_match_the_quarter_car(car):
    from nodes.plant.double_wishbone import DoubleWishboneCorner

    W = car.static_tyre_load()
    car.substep(1e-3, W, 3800.0 * car.state()["v_damper"])
    loads = car.corner_arm_loads()
    fl, fr = loads["FL"], loads["FR"]
    for k, v in fl.items():  # the right arm in its mirrored frame carries the left's loads
        assert fr[k] == pytest.approx(v, rel=5e-5, abs=5e-3), k  # solver noise (the rack's)
    # each arm in balance with its weight (static): forces in its frame, z up
    for name in ("FL", "FR", "RL", "RR"):
        a = loads[name]
        for ax in "xyz":
            total = sum(a[f"{pt}_{ax}"] for pt in ("ball_joint", "damper_mount", "bush_front",
                                                   "bush_rear"))
            total += a.get(f"bump_stop_{ax}", 0.0)
            weight = 5.0 * GRAVITY if ax == "z" else 0.0
            assert total == pytest.approx(weight, abs=0.05), (name, ax)
    # the front corner is the quarter car under its (0.03 % smaller) static load
    q = DoubleWishboneCorner()
    try:
        q.substep(1e-3, q.static_tyre_load(), 3800.0 * q.state()["v_damper"])
        lq = q.loads()["arm"]
    finally:
        q.close()
    for k in ("ball_joint_z", "bush_front_z", "bush_rear_z", "torsion_bar_mx"):
        assert fl[k] == pytest.approx(lq[k], rel=1e-3), k


def test_heave_is_the_corner_checks_quarter_car_and_left_equals_right():
    m = FullVehicleDoubleWishbone(DECOUPLED)
    try:
        W, dt, n = m.static_tyre_load(), 2e-3, 900
        heave, zw = np.empty(n), np.empty((n, 4))
        for k in range(n):  # a 10 mm road step under all four wheels, no damper
            st = m.state()
            m.substep(dt, np.maximum(0.0, W + K_T * (0.01 - st["z_w"])), np.zeros(4))
            st = m.state()
            heave[k], zw[k] = st["heave"][0], st["z_w"]
            assert abs(st["roll"][0]) < 1e-6 and abs(st["pitch"][0]) < 1e-5
        loads = m.corner_arm_loads()
    finally:
        m.close()
    assert np.abs(zw[:, 0] - zw[:, 1]).max() < 1e-6  # mirrored corners move alike
    for k, v in loads["FL"].items():  # and their arms carry mirrored loads in motion too
        assert loads["FR"][k] == pytest.approx(v, rel=1e-4, abs=1e-2), k
    # period of the body mode from the up-crossings of the oscillation about 10 mm
    x = heave - 0.01
    up = np.where((x[:-1] < 0) & (x[1:] >= 0))[0]
    t_up = (up + x[up] / (x[up] - x[up + 1])) * dt
    f_meas = 1.0 / np.mean(np.diff(t_up))
    # the 2-DOF quarter car: m_s = M/4, m_u, k_s = the corner check's wheel rate, k_t
    eq = ck.equivalent_quarter_car(cf.builtin())
    ms, mu, ks = M / 4, eq["m_u"], eq["k_s"]
    Mm = np.diag([ms, mu])
    K = np.array([[ks, -ks], [-ks, ks + K_T]])
    f_body = np.sqrt(np.linalg.eigvals(np.linalg.solve(Mm, K)).real.min()) / (2 * np.pi)
    assert f_meas == pytest.approx(f_body, rel=0.015)


def test_the_factory_builds_it_from_corner_files(tmp_path):
    wide = str(cf.BUILTIN.parent.parent.parent / "tests" / "vehicles" / "corners"
               / "wide_track.toml")
    m = build_plant_model({"model": "full_vehicle_double_wishbone", "rear": wide,
                           "sprung_mass": 1900.0})
    try:
        info = m.info()
        assert info["corners"][2] == "wide_track" and info["body_mass"] == 1900.0
        assert m.wheel_centres[2, 1] == 0.78 and m.wheel_centres[3, 1] == -0.78
        assert m.wheel_centres[0, 1] == 0.7055
    finally:
        m.close()
