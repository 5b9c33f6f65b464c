"""Double-wishbone corner: equilibrium at t = 0, arm-load extraction and the arm's balance
(static, and with its inertia in bumper contact), closed loop."""

import numpy as np
import pytest

from nodes.plant.double_wishbone import (
    ARM_POINTS,
    LOWER_ARM_COM,
    LOWER_BUSH_FRONT,
    DoubleWishboneCorner,
    arm_frame,
    to_arm_frame,
)

from ._sim import arm_balance_residuals


@pytest.fixture(scope="module")
def corner():
    m = DoubleWishboneCorner()
    yield m
    m.close()


def test_stays_in_static_equilibrium(corner):
    W = corner.static_tyre_load()
    assert W[0] == pytest.approx((535 + 47.75) * 9.81)
    worst: dict[str, float] = {}
    for _ in range(1000):
        corner.substep(1e-3, W, np.zeros(1))
        for key, v in corner.state().items():
            worst[key] = max(worst.get(key, 0.0), abs(float(v[0])))
    # what remains is a bounded micro-oscillation left by the iterative constraint solver
    for key in ("z_b", "z_w", "z_damper"):
        assert worst[key] < 2e-6, key   # metres: 2 micrometres
    assert worst["arm_angle"] < 5e-6
    for key in ("v_b", "v_w", "v_damper"):
        assert worst[key] < 2e-5, key


def _point_forces(L: dict[str, float]) -> dict[str, np.ndarray]:
    """The arm's point loads (arm frame) by load point; the bump stop has no x component."""
    out = {}
    for k in ARM_POINTS:
        out[k] = np.array([L.get(f"{k}_{a}", 0.0) for a in "xyz"])
    assert "bump_stop_x" not in L and {"bump_stop_y", "bump_stop_z"} <= set(L)
    return out


def test_static_arm_loads_balance_the_arm_weight(corner):
    corner.substep(1e-3, corner.static_tyre_load(), np.zeros(1))
    L = corner.loads()["arm"]
    pts = {k: to_arm_frame(v) for k, v in ARM_POINTS.items()}
    F = _point_forces(L)
    _, R = arm_frame()
    g_arm = R.T @ np.array([0.0, 0.0, -5.0 * 9.81])  # arm weight in the arm frame
    total = sum(F.values())
    assert np.allclose(total + g_arm, 0.0, atol=0.5)  # |F| ~ 5 kN: 1e-4 relative
    # moments about the arm origin close with the torsion-bar moment about x
    com = to_arm_frame(LOWER_ARM_COM)
    M = sum(np.cross(pts[k], F[k]) for k in pts) + np.cross(com, g_arm)
    M[0] += L["torsion_bar_mx"]
    assert np.allclose(M, 0.0, atol=0.5)
    # the torsion bar carries the static preload, the ball joint the wheel load; the jounce
    # bumper is clear at ride height
    assert L["torsion_bar_mx"] == pytest.approx(corner.tau0, rel=1e-3)
    assert L["ball_joint_z"] > 4000.0
    assert L["bush_front_z"] + L["bush_rear_z"] < -4000.0
    assert L["bump_stop_y"] == 0.0 and L["bump_stop_z"] == 0.0
    # torsion-bar preload: the body's weight times the wheel-centre lever (0.2984 m from the
    # front-view kinematics, docstring of double_wishbone); the linkage's weight adds ~1.4 %
    assert corner.tau0 == pytest.approx(-535 * 9.81 * 0.2984, rel=0.03)


def test_arm_balance_with_its_inertia_in_bumper_contact(big_bump):
    """Every load on the arm (ball joint, damper, bushes, bump stop, torsion-bar moment) and
    its weight against its inertia, m a_com and I alpha + w x I w, while the bumper pushes
    (F_bs up to 8.8 kN)."""
    recs, dt = big_bump
    resF, resM, resF_nobump = [], [], []
    peak = 0.0
    for r in recs:
        f, mo = arm_balance_residuals(r, dt)
        resF.append(np.abs(f).max())
        resM.append(np.abs(mo).max())
        if r["F_bs"] > 1000.0:
            resF_nobump.append(np.abs(arm_balance_residuals(r, dt, with_bump=False)[0]).max())
        peak = max(peak, abs(r["L"]["ball_joint_z"]))
    # ball joint up to ~15 kN; the balance closes to 0.35 % of it (PyBullet's joint sensors
    # carry a small velocity-dependent error, docs/vehicles_roads.md)
    assert peak > 8000.0
    assert max(resF) < 0.0035 * peak
    assert max(resM) < 3.0
    # leaving the bump-stop load out breaks the balance by kN: the check sees it
    assert min(resF_nobump) > 20 * max(resF)


def test_arm_frame_definition():
    o, R = arm_frame()
    assert np.allclose(R.T @ R, np.eye(3))
    assert np.allclose(to_arm_frame(LOWER_BUSH_FRONT)[1:], 0.0)  # bushes on the x axis
    bj = to_arm_frame(ARM_POINTS["ball_joint"])
    assert bj[1] == pytest.approx(0.294) and abs(bj[2]) < 1e-12  # y out to the ball joint
    assert R[2, 2] > 0.99  # left corner: arm z is (nearly) up


def test_bump_moves_wheel_through_the_loop_and_damper_dissipates():
    m = DoubleWishboneCorner()
    W = m.static_tyre_load()
    k_t, c = 239000.0, 3800.0
    zb, zw, zd = [], [], []
    for k in range(1500):
        st = m.state()
        z_g = 0.01 if k * 1e-3 >= 0.05 else 0.0
        F_t = np.maximum(0.0, W + k_t * (z_g - st["z_w"]))
        m.substep(1e-3, F_t, c * st["v_damper"])
        st = m.state()
        zb.append(st["z_b"][0])
        zw.append(st["z_w"][0])
        zd.append(st["z_damper"][0])
    loads = m.loads()["arm"]
    m.close()
    zw, zd = np.array(zw), np.array(zd)
    # damper compresses with about the motion ratio 0.63 of the wheel travel relative to body
    rel = zw - np.array(zb)
    i = np.argmax(np.abs(rel))
    assert 0.5 < zd[i] / rel[i] < 0.72
    assert abs(zb[-1] - 0.01) < 0.004 and abs(zw[-1] - 0.01) < 0.002  # settling on the step
    assert np.all(np.isfinite(list(loads.values())))
