"""Appendix II log decrement: round trips on known systems, the realistic corner against
Table 4.3, and the command's --json."""

import json

import numpy as np
import pytest

from nodes.plant.equivalent_lumped import (
    K_T,
    TABLE_4_3,
    identify,
    log_decrement,
    simulate,
    two_dof_equivalent,
)
from nodes.plant.quarter_car_lumped import LumpedQuarterCar, LumpedQuarterCarParams


def test_round_trip_on_the_table_4_3_sdof():
    m, k, c = 535.0, 31000.0, 1500.0
    wn = np.sqrt(k / m)
    zeta = c / (2 * np.sqrt(k * m))
    wd = wn * np.sqrt(1 - zeta ** 2)
    t = np.arange(0, 5, 1e-3)
    x = 0.01 * np.exp(-zeta * wn * t) * np.cos(wd * t)
    ld = log_decrement(t, x)
    assert ld["zeta"] == pytest.approx(0.184, abs=0.002)
    assert m * ld["omega_n"] ** 2 == pytest.approx(k, rel=0.01)
    assert ld["zeta"] * 2 * np.sqrt(m * ld["omega_n"] ** 2 * m) == pytest.approx(c, rel=0.02)
    assert np.exp(ld["delta"]) == pytest.approx(3.25, abs=0.05)


def _body_mode(m_b, m_w, k_s, c_s, k_t):
    """Body-mode natural frequency [rad/s] and damping ratio of the 2-DOF, by eigenvalues."""
    M = np.diag([m_b, m_w])
    K = np.array([[k_s, -k_s], [-k_s, k_s + k_t]])
    C = np.array([[c_s, -c_s], [-c_s, c_s]])
    A = np.block([[np.zeros((2, 2)), np.eye(2)],
                  [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    ev = np.linalg.eigvals(A)
    s = ev[np.argmin(np.abs(ev))]
    return abs(s), -s.real / abs(s)


def test_two_dof_equivalent_inverts_the_body_mode_exactly():
    wn, zeta = _body_mode(535.0, 47.75, 31000.0, 1500.0, 239000.0)
    # the 2-DOF body mode: 1.146 Hz, zeta 0.154 (Ch. 4 extraction); the single-DOF App. II
    # formula on it gives the ride rate, not k_s
    assert wn / (2 * np.pi) == pytest.approx(1.146, abs=0.001)
    assert zeta == pytest.approx(0.154, abs=0.001)
    assert 535.0 * wn ** 2 == pytest.approx(27400, rel=0.02)
    k_s, c_s = two_dof_equivalent(535.0, 47.75, 239000.0, wn, zeta)
    assert k_s == pytest.approx(31000.0, rel=1e-9)
    assert c_s == pytest.approx(1500.0, rel=1e-9)


def test_log_decrement_on_the_lumped_table_4_3_quarter_car_returns_table_4_3():
    """The whole procedure (road step, log decrement, 2-DOF inversion) on a PyBullet lumped
    quarter car whose answer is known."""
    lq = LumpedQuarterCar(LumpedQuarterCarParams(535.0, 47.75, 31000.0))
    try:
        r = simulate(lq, 4.0, 2e-3, lambda t: 0.01 if t >= 0.05 else 0.0,
                     lambda st: 1500.0 * float(st["v_w"][0] - st["v_b"][0]))
    finally:
        lq.close()
    ld = log_decrement(r["t"], r["z_b"] - 0.01)
    k_s, c_s = two_dof_equivalent(535.0, 47.75, K_T, ld["omega_n"], ld["zeta"])
    assert k_s == pytest.approx(31000.0, rel=0.01)
    assert c_s == pytest.approx(1500.0, rel=0.01)


@pytest.fixture(scope="module")
def corner_eq():
    return identify(step=0.01, dt=2e-3, t_end=4.0)


def test_identify_on_the_realistic_corner_meets_table_4_3(corner_eq):
    eq = corner_eq
    assert eq["m_w"] == pytest.approx(47.75)
    assert eq["m_b"] == 535.0
    # the bars: k_s within 10 %, c_s within 15 % of Table 4.3
    assert eq["k_s"] == pytest.approx(TABLE_4_3["k_s"], rel=0.10)
    assert eq["c_s"] == pytest.approx(TABLE_4_3["c_s"], rel=0.15)
    # and the geometry's own prediction, K_theta / L^2 with the ball-joint lever 0.294 m
    # (the wheel centre's lever is 1.5 % longer: -3 %) and 3800 (0.628 cos 4 deg)^2
    assert eq["k_s_lever"] == pytest.approx(30983, rel=1e-3)
    assert eq["k_s"] == pytest.approx(eq["k_s_lever"], rel=0.06)
    assert eq["c_s"] == pytest.approx(eq["c_s_lever"], rel=0.06)
    # Appendix II's single-DOF formula gives the ride rate (Table 4.3's text: 27.4 kN/m)
    assert eq["k_s_app2"] == pytest.approx(TABLE_4_3["ride_rate"], rel=0.05)
    assert 0.13 < eq["zeta"] < 0.18


def test_equivalent_lumped_json(capsys):
    from orchestrator.studies.equivalent_lumped import main

    assert main(["--json", "--no-compare", "--dt", "0.002"]) == 0
    out = json.loads(capsys.readouterr().out)
    for key in ("k_s", "c_s", "m_s", "m_u", "k_t", "zeta", "f_n", "k_s_app2", "table_4_3"):
        assert key in out, key
    assert out["m_s"] == 535.0 and out["m_u"] == pytest.approx(47.75)
    assert out["k_s"] == pytest.approx(31000.0, rel=0.10)
    assert out["c_s"] == pytest.approx(1500.0, rel=0.15)
    assert out["k_s_error_pct"] == pytest.approx(100 * (out["k_s"] / 31000.0 - 1))
    assert out["table_4_3"]["k_s"] == 31000.0
    assert 0.9 < out["f_n"] < 1.3
