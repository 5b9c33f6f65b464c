"""Double-wishbone corner: equilibrium at t = 0, arm-load extraction and the arm's balance
(static, and with its inertia in bumper contact), closed loop."""

import numpy as np
import pytest

from nodes.plant.double_wishbone import DoubleWishboneCorner
from nodes.plant.double_wishbone_geometry import BUILTIN

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
    for k in BUILTIN.arm_points:
        out[k] = np.array([L.get(f"{k}_{a}", 0.0) for a in "xyz"])
    assert "bump_stop_x" not in L and {"bump_stop_y", "bump_stop_z"} <= set(L)
    return out


def test_static_arm_loads_balance_the_arm_weight(corner):
    corner.substep(1e-3, corner.static_tyre_load(), np.zeros(1))
    L = corner.loads()["arm"]
    pts = {k: BUILTIN.to_arm_frame(v) for k, v in BUILTIN.arm_points.items()}
    F = _point_forces(L)
    R = BUILTIN.arm_rotation
    g_arm = R.T @ np.array([0.0, 0.0, -5.0 * 9.81])  # arm weight in the arm frame
    total = sum(F.values())
    assert np.allclose(total + g_arm, 0.0, atol=0.5)  # |F| ~ 5 kN: 1e-4 relative
    # moments about the arm origin close with the torsion-bar moment about x
    com = BUILTIN.to_arm_frame(BUILTIN.lower_arm_com)
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
    R = BUILTIN.arm_rotation
    assert np.allclose(R.T @ R, np.eye(3))
    assert np.allclose(BUILTIN.to_arm_frame(BUILTIN.lower_bush_front)[1:], 0.0)  # on the x axis
    bj = BUILTIN.to_arm_frame(BUILTIN.arm_points["ball_joint"])
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


def _upper_arm_run(dt: float = 5e-4, t_end: float = 0.3):
    """The corner over the 100 mm x 1.0 m bump at 34 km/h (as big_bump), recording the upper
    arm's loads and its link's pose and velocities before and after each substep."""
    import pybullet as p

    from nodes.plant import double_wishbone as dw

    m = DoubleWishboneCorner()

    def link():
        ls = p.getLinkState(m.body, dw.UPPER_ARM, computeLinkVelocity=1,
                            computeForwardKinematics=1, physicsClientId=m.client)
        R = np.array(p.getMatrixFromQuaternion(ls[5])).reshape(3, 3)
        return np.array(ls[0]), np.array(ls[4]), R, np.array(ls[6]), np.array(ls[7])

    W, v = m.static_tyre_load(), 34.0 / 3.6

    def road(t):
        u = v * t - 1.0
        return 0.05 * (1 - np.cos(2 * np.pi * u)) if 0 <= u <= 1 else 0.0

    recs = []
    try:
        for k in range(int(round(t_end / dt))):
            st = m.state()
            F_t = np.maximum(0.0, W + 239000.0 * (road(k * dt) - st["z_w"]))
            before = link()
            m.substep(dt, F_t, 3800.0 * st["v_damper"])
            recs.append((m.loads()["upper_arm"], before, link()))
    finally:
        m.close()
    return recs, dt


def test_upper_arm_loads_balance_its_weight_and_inertia():
    """plant/upper_arm (ball joint and both bushes, upper-arm frame) with the arm's weight
    against its inertia, m a_com and I alpha + w x I w, static and over a 100 mm bump; and
    the frame is the corner file's upper points' (the lower arm's rule)."""
    from cosim import corner
    from cosim.schema import columns
    from nodes.plant.upper_arm_loads import FIELDS, upper_arm_frame, upper_hardpoints

    cf = corner.builtin()
    o, Rf = upper_arm_frame(cf)
    hp = upper_hardpoints(cf)
    assert np.allclose(Rf.T @ Rf, np.eye(3)) and np.allclose(o, [0.0, -0.34, 0.18])
    assert np.allclose(hp["upper_bush_front"], [0.14, 0, 0])
    bj = hp["upper_ball_joint"]
    assert bj[2] == pytest.approx(0.0, abs=1e-12)
    assert bj[1] == pytest.approx(np.hypot(0.24, 0.02))  # 0.2408 m from the pivot axis
    assert np.allclose(o + Rf @ bj, cf.points["upper_ball_joint"])
    assert [f"plant/upper_arm/{f}" for f in FIELDS] == columns("plant", "upper_arm")
    mass = cf.masses["upper_arm"]
    inertia = np.diag([0.012, 0.01, 0.02])  # the URDF's (double_wishbone_geometry.urdf)
    recs, dt = _upper_arm_run()
    resF, resM, resF_noball, peak = [], [], [], 0.0
    for L, (com0, O0, R0, v0, w0), (_, _, _, v1, w1) in recs:
        assert set(L) == set(FIELDS)
        F = np.array([0.0, 0.0, -mass * 9.81])
        M = np.zeros(3)
        F_ball = np.zeros(3)
        for name in ("upper_ball_joint", "upper_bush_front", "upper_bush_rear"):
            f = R0 @ Rf @ np.array([L[f"{name}_{a}"] for a in "xyz"])
            r = O0 + R0 @ Rf @ hp[name]
            F += f
            M += np.cross(r - com0, f)
            if name == "upper_ball_joint":
                F_ball = f
        a, alpha = (v1 - v0) / dt, (w1 - w0) / dt
        Iw = R0 @ inertia @ R0.T
        resF.append(np.abs(F - mass * a).max())
        resM.append(np.abs(M - (Iw @ alpha + np.cross(w0, Iw @ w0))).max())
        resF_noball.append(np.abs(F - F_ball - mass * a).max())
        peak = max(peak, float(np.abs(F_ball).max()))
    # static (the first substep): exact to the solver's rounding; the weight on the ball
    # joint is a third (the centre of mass at the points' centroid, a free pivot)
    assert resF[0] < 1e-3 and resM[0] < 1e-3  # N, N m (loads of ~1 kN)
    assert recs[0][0]["upper_ball_joint_z"] == pytest.approx(mass * 9.81 * np.cos(
        np.arctan2(0.02, 0.24)) / 3, rel=1e-3)
    # over the bump: the ball joint's force reaches ~5 kN; the balance closes to 0.4 % of it
    # (PyBullet's joint sensors, as the lower arm's) and 1 N m
    assert peak > 4000.0
    assert max(resF) < 0.004 * peak
    assert max(resM) < 1.0
    # without the ball joint's load the balance is off by its kN: the check sees it
    assert resF_noball[0] > 500.0 and max(resF_noball) > 100 * max(resF)
