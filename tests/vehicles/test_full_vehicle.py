"""7-DOF full vehicle: static equilibrium at t = 0, geometry in info(), FR-only input."""

import numpy as np
import pytest

from nodes.plant.full_vehicle_7dof import FullVehicle7DOF, FullVehicleParams

from ._sim import run_closed_loop


def test_starts_and_stays_in_static_equilibrium():
    model = FullVehicle7DOF()
    W = model.static_tyre_load()
    assert W.sum() == pytest.approx((1870 + 4 * 47.8) * 9.81)
    for _ in range(2000):
        model.substep(1e-3, W, np.zeros(4))
    st = model.state()
    model.close()
    for key in ("z_b", "z_w", "heave", "pitch", "roll", "v_b", "v_w"):
        assert np.abs(st[key]).max() < 1e-9, key


def test_info_gives_wheel_paths():
    pr = FullVehicleParams()
    model = FullVehicle7DOF(pr)
    info = model.info()
    model.close()
    assert info["corner_names"] == ["FL", "FR", "RL", "RR"]
    assert info["wheel_x"] == [0.0, 0.0, -2.774, -2.774]
    assert info["wheel_track"] == [0, 1, 0, 1]
    assert info["n_corners"] == 4
    # CG where the static corner loads balance: 2*535*a = 2*400*b
    assert 535 * info["cg_to_front_axle"] == pytest.approx(400 * (2.774 - pr.a))


def test_front_right_step_statics_and_independence():
    """A 10 mm step under FR only: transient stays at FR mostly, and the settled body
    attitude equals the rigid body on four series springs k_s k_t/(k_s+k_t)."""
    pr = FullVehicleParams()
    model = FullVehicle7DOF(pr)
    zg = np.array([0.0, 0.01, 0.0, 0.0])
    r = run_closed_loop(model, 8.0, 2e-3, 239000.0, 1500.0, lambda t: zg)
    model.close()
    zw = r["z_w"]
    assert np.abs(zw[:, 1]).max() > 3 * np.abs(zw[:, [0, 2, 3]]).max()
    rr = 31000.0 * 239000.0 / 270000.0
    J = np.array([[1.0, -x, y] for x, y in pr.corner_xy])
    q = np.linalg.solve(rr * J.T @ J, rr * J.T @ zg)
    assert r["heave"][-1, 0] == pytest.approx(q[0], rel=0.02)
    assert r["pitch"][-1, 0] == pytest.approx(q[1], rel=0.02)
    assert r["roll"][-1, 0] == pytest.approx(q[2], rel=0.02)
    assert r["roll"][-1, 0] < 0  # right side up = negative roll (ISO 8855, +x axis)
    assert r["z_b"][-1] == pytest.approx(J @ q, abs=2e-4)
