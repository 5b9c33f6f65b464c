"""Natural frequencies of the lumped models, measured from simulated free responses of the
PyBullet models, against the closed forms of Appendix III (Eqs. A3.1-A3.5)."""

import numpy as np
import pytest

from nodes.plant.full_vehicle_7dof import FullVehicle7DOF, FullVehicleParams
from nodes.plant.quarter_car_lumped import LumpedQuarterCar, LumpedQuarterCarParams

from ._sim import peak_frequency, run_closed_loop


def appendix_iii(m_b, m_w, k_s, k_t):
    rr = k_s * k_t / (k_s + k_t)
    return np.sqrt(rr / m_b) / (2 * np.pi), np.sqrt((k_s + k_t) / m_w) / (2 * np.pi)


@pytest.mark.parametrize("m_b,m_w,k_s,k_t,f1_thesis,f2_thesis", [
    (317.5, 45.4, 22000.0, 192000.0, 1.255, 10.93),    # Crolla et al. (Table 3.1)
    (535.0, 47.75, 31000.0, 239000.0, 1.140, 11.97),   # MPV (Table 4.3)
])
def test_quarter_car_free_response_frequencies(m_b, m_w, k_s, k_t, f1_thesis, f2_thesis):
    f1, f2 = appendix_iii(m_b, m_w, k_s, k_t)
    assert f1 == pytest.approx(f1_thesis, abs=0.001)
    assert f2 == pytest.approx(f2_thesis, abs=0.005)
    model = LumpedQuarterCar(LumpedQuarterCarParams(m_b, m_w, k_s))
    dt = 1e-3
    # free response after a 5 mm road step at t = 0, undamped (c_s = 0)
    r = run_closed_loop(model, 20.0, dt, k_t, 0.0, lambda t: np.array([0.005]))
    model.close()
    assert r["F_t"].min() > 0  # stayed in contact: a linear free response
    f_body = peak_frequency(r["z_b"][:, 0], dt, 0.5, 3.0)
    f_hop = peak_frequency(r["z_w"][:, 0] - r["z_b"][:, 0], dt, 5.0, 20.0)
    # Appendix III decouples the modes; the exact 2-DOF values lie within 0.2 %
    assert f_body == pytest.approx(f1, rel=0.005)
    assert f_hop == pytest.approx(f2, rel=0.005)


def _full_vehicle_eigenfrequencies(pr: FullVehicleParams, k_t: float) -> np.ndarray:
    """Undamped eigenfrequencies [Hz] of the linear 7-DOF equations written out by hand
    (Sec. 4 of the Ch. 4 extraction, ISO signs): q = (z, theta, phi, z_w1..4)."""
    k_s = pr.spring_stiffness
    M = np.diag([pr.body_mass, pr.pitch_inertia, pr.roll_inertia] + [pr.unsprung_mass] * 4)
    K = np.zeros((7, 7))
    for i, (x, y) in enumerate(pr.corner_xy):
        d = np.zeros(7)
        d[:3] = [1.0, -x, y]
        d[3 + i] = -1.0
        K += k_s * np.outer(d, d)
        K[3 + i, 3 + i] += k_t
    return np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(M, K)).real)) / (2 * np.pi)


def test_full_vehicle_body_modes_match_the_linear_7dof():
    pr = FullVehicleParams()
    f = _full_vehicle_eigenfrequencies(pr, 239000.0)
    dt = 2e-3
    model = FullVehicle7DOF(pr)  # heave input: heave-pitch mode (lowest)
    r = run_closed_loop(model, 20.0, dt, 239000.0, 0.0, lambda t: np.full(4, 0.005))
    model.close()
    assert peak_frequency(r["heave"][:, 0], dt, 0.5, 3.0) == pytest.approx(f[0], rel=0.005)
    assert abs(r["roll"]).max() < 1e-9  # symmetric input: no roll
    model = FullVehicle7DOF(pr)  # left/right antisymmetric input: roll mode only
    r = run_closed_loop(model, 20.0, dt, 239000.0, 0.0,
                        lambda t: np.array([0.005, -0.005, 0.005, -0.005]))
    model.close()
    assert peak_frequency(r["roll"][:, 0], dt, 0.5, 3.0) == pytest.approx(f[1], rel=0.005)
    assert abs(r["heave"]).max() < 1e-6
    assert f[3] == pytest.approx(11.97, abs=0.02)  # wheel hop stays at the QVM value
