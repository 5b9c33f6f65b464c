"""Issue #27 item 1: the 7-DOF body's mass and inertias from one basis (point masses at the
corners, Sec. 4.4), its dynamic index, and its heave / pitch / roll frequencies against the
closed forms of a rigid body on four ride-rate springs (Gillespie's bounce-pitch pair and the
roll mode), checked on the PyBullet model's free response."""

import numpy as np
import pytest

from nodes.plant.full_vehicle_7dof import FullVehicle7DOF, FullVehicleParams

from ._sim import peak_frequency, run_closed_loop

K_T = 239000.0  # N/m, Table 4.4


def _closed_form(pr: FullVehicleParams) -> dict[str, float]:
    """Body-mode frequencies [Hz] of a rigid body (M, I_p, I_r) on four corner springs of the
    ride rate RR = k_s k_t / (k_s + k_t) (wheel inertia neglected):
    bounce-pitch: w^2 = (alpha + gamma)/2 -/+ sqrt((alpha - gamma)^2/4 + beta^2 M / I_p),
    alpha = 4 RR / M, beta = 2 RR (b - a) / M, gamma = 2 RR (a^2 + b^2) / I_p;
    roll: w^2 = 4 RR (t/2)^2 / I_r."""
    rr = pr.spring_stiffness * K_T / (pr.spring_stiffness + K_T)
    M, Ip, Ir = pr.body_mass, pr.I_pitch, pr.I_roll
    a = pr.a
    b = pr.wheelbase - a
    alpha, beta, gamma = 4 * rr / M, 2 * rr * (b - a) / M, 2 * rr * (a * a + b * b) / Ip
    root = np.sqrt((alpha - gamma) ** 2 / 4 + beta**2 * M / Ip)
    w_lo, w_hi = (alpha + gamma) / 2 - root, (alpha + gamma) / 2 + root
    w_roll = np.sqrt(4 * rr * (pr.track / 2) ** 2 / Ir)
    to_hz = 1 / (2 * np.pi)
    return {"bp_lo": np.sqrt(w_lo) * to_hz, "bp_hi": np.sqrt(w_hi) * to_hz,
            "roll": w_roll * to_hz, "front": np.sqrt(rr / pr.sprung_mass_front) * to_hz,
            "rear": np.sqrt(rr / pr.sprung_mass_rear) * to_hz}


def test_one_basis_inertias_and_a_dynamic_index_of_one():
    pr = FullVehicleParams()
    assert pr.body_mass == pytest.approx(1870.0)
    a, b, h = pr.a, pr.wheelbase - pr.a, pr.track / 2
    # point masses 535, 535, 400, 400 kg at (a, +-t/2), (-b, +-t/2)
    assert pr.I_pitch == pytest.approx(2 * 535 * a**2 + 2 * 400 * b**2, rel=1e-12)
    assert pr.I_roll == pytest.approx(1870 * h**2, rel=1e-12)
    assert pr.I_pitch == pytest.approx(3522.5, abs=0.1)
    assert pr.I_roll == pytest.approx(930.8, abs=0.1)
    assert pr.dynamic_index == pytest.approx(1.0, rel=1e-12)
    # the per-axle reading of the same formula is what Table 4.4 prints (1761.3 / 465.3)
    ax = FullVehicleParams(mass_basis="axle")
    assert ax.I_pitch == pytest.approx(1761.3, rel=1e-3)
    assert ax.I_roll == pytest.approx(465.3, rel=1e-3)
    # the old default (corner masses with the axle inertias) had a dynamic index of 0.5
    old = FullVehicleParams(pitch_inertia=1761.3, roll_inertia=465.3)
    assert old.dynamic_index == pytest.approx(0.5, abs=0.001)
    # a scenario's explicit inertia is kept
    assert FullVehicleParams(pitch_inertia=3000.0).I_pitch == 3000.0


def test_closed_forms_agree_with_the_linear_7dof_eigenvalues():
    """The closed forms (no wheel inertia) against the undamped 7-DOF eigenvalues written out
    independently (within 0.5 %): with a dynamic index of 1 the bounce-pitch pair is the front
    and rear corners' own modes sqrt(RR / m_f) = 1.140 Hz and sqrt(RR / m_r) = 1.318 Hz, and
    the roll mode equals the mean heave sqrt(4 RR / M) = 1.219 Hz."""
    pr = FullVehicleParams()
    cf = _closed_form(pr)
    assert cf["bp_lo"] == pytest.approx(cf["front"], rel=1e-9)
    assert cf["bp_hi"] == pytest.approx(cf["rear"], rel=1e-9)
    assert cf["front"] == pytest.approx(1.140, abs=0.001)  # Appendix III's MPV
    assert cf["rear"] == pytest.approx(1.318, abs=0.001)
    assert cf["roll"] == pytest.approx(1.219, abs=0.001)
    k_s = pr.spring_stiffness
    M = np.diag([pr.body_mass, pr.I_pitch, pr.I_roll] + [pr.unsprung_mass] * 4)
    K = np.zeros((7, 7))
    for i, (x, y) in enumerate(pr.corner_xy):
        d = np.zeros(7)
        d[:3] = [1.0, -x, y]
        d[3 + i] = -1.0
        K += k_s * np.outer(d, d)
        K[3 + i, 3 + i] += K_T
    f = np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(M, K)).real)) / (2 * np.pi)
    assert sorted(f[:3]) == pytest.approx(sorted([cf["bp_lo"], cf["roll"], cf["bp_hi"]]),
                                          rel=0.005)


def test_pybullet_free_response_at_the_closed_form_frequencies():
    """Undamped free responses of the PyBullet model after 5 mm road steps: a front-axle
    step rings the front corners at the front mode and leaves the rear corners still (nodes at
    the rear axle: the dynamic index of 1 decouples the axles); a rear-axle step the rear mode;
    a left/right antisymmetric step the roll mode."""
    pr = FullVehicleParams()
    cf = _closed_form(pr)
    dt, t_end = 2e-3, 12.0
    cases = {"front": np.array([0.005, 0.005, 0.0, 0.0]),
             "rear": np.array([0.0, 0.0, 0.005, 0.005]),
             "roll": np.array([0.005, -0.005, 0.005, -0.005])}
    runs = {}
    for name, zg in cases.items():
        model = FullVehicle7DOF(pr)
        runs[name] = run_closed_loop(model, t_end, dt, K_T, 0.0, lambda t, zg=zg: zg)
        model.close()
    front, rear, roll = runs["front"], runs["rear"], runs["roll"]
    assert peak_frequency(front["z_b"][:, 0], dt, 0.5, 3.0) == pytest.approx(cf["front"],
                                                                             rel=0.005)
    assert np.abs(front["z_b"][:, 2:]).max() < 0.01 * np.abs(front["z_b"][:, :2]).max()
    assert peak_frequency(rear["z_b"][:, 2], dt, 0.5, 3.0) == pytest.approx(cf["rear"],
                                                                            rel=0.005)
    assert np.abs(rear["z_b"][:, :2]).max() < 0.01 * np.abs(rear["z_b"][:, 2:]).max()
    assert peak_frequency(roll["roll"][:, 0], dt, 0.5, 3.0) == pytest.approx(cf["roll"],
                                                                             rel=0.005)
    assert np.abs(roll["heave"]).max() < 1e-6 and np.abs(roll["pitch"]).max() < 1e-6
