"""The realistic corner's lower-arm point accelerations (``a_arm_{loc1,cg,loc2}_{x,y,z}`` in
``plant/response``, thesis Table 5.4): zero at static equilibrium, the rigid arm's kinematics
(the body's heave plus the arm's rotation about its pivot axis) in motion, so the vertical
acceleration grows with the distance from the pivot axis (Loc1 > CG > Loc2); and the plant
node publishes them in a run."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pybullet as p

from cosim.table import read_table
from nodes.plant import double_wishbone as dw
from nodes.plant import double_wishbone_geometry as geo

from ..conftest import ROOT, suscosim

DT = 5e-4
NAMES = ("loc1", "cg", "loc2")


def _accels(m, F_t, F_d):
    """One substep; the node's difference quotient of the point velocities, and the body's
    and the arm joint's (angle, rate) before and after."""
    v0 = m.response_velocities()
    j0 = p.getJointState(m.body, dw.LOWER_ARM, physicsClientId=m.client)[:2]
    vb0 = m.state()["v_b"][0]
    m.substep(DT, F_t, F_d)
    v1 = m.response_velocities()
    j1 = p.getJointState(m.body, dw.LOWER_ARM, physicsClientId=m.client)[:2]
    vb1 = m.state()["v_b"][0]
    acc = {k: float(v1[k] - v0[k]) / DT for k in v0}
    return acc, (vb1 - vb0) / DT, j0, j1


def test_points_are_where_the_docstring_says():
    pts = geo.BUILTIN.arm_accel_points
    np.testing.assert_allclose(pts["loc1"], dw.la.BALL_JOINT - [0, 0.020, 0])
    np.testing.assert_allclose(pts["loc2"], [0, 0.020, 0])
    np.testing.assert_allclose(pts["cg"], dw.la.MASS_PROPERTIES["centre_of_mass_m"])


def test_zero_at_static_equilibrium():
    m = dw.DoubleWishboneCorner()
    try:
        W = m.static_tyre_load()
        worst = 0.0
        for _ in range(200):  # 0.1 s at rest
            acc, _, _, _ = _accels(m, W, np.zeros(1))
            worst = max(worst, max(abs(v) for v in acc.values()))
    finally:
        m.close()
    assert len(acc) == 9
    assert worst < 1e-3  # m/s^2 (a bump gives tens)


def test_rigid_arm_kinematics_over_a_bump():
    """The corner over a 40 mm 1-cos bump (passive 3800 N s/m on v_damper): every point's
    acceleration is the body's heave plus the arm's rotation about the pivot axis x,
    r (alpha cos(theta) - omega^2 sin(theta)) vertically, from the joint's own angle and rate;
    so z scales with the distance r from the axis and Loc1 > CG > Loc2 in RMS."""
    m = dw.DoubleWishboneCorner()
    W, v = m.static_tyre_load(), 34.0 / 3.6
    theta0 = m._theta0

    def road(t):
        u = (v * t - 0.2) / 0.8
        return 0.5 * 0.04 * (1 - np.cos(2 * np.pi * u)) if 0 <= u <= 1 else 0.0

    rows = []
    try:
        for k in range(int(0.5 / DT)):
            st = m.state()
            F_t = np.maximum(0.0, W + 239000.0 * (road(k * DT) - st["z_w"]))
            acc, a_b, (th0, w0), (th1, w1) = _accels(m, F_t, 3800.0 * st["v_damper"])
            rows.append((acc, a_b, th0 - theta0, w0, th1 - theta0, w1))
    finally:
        m.close()
    z = {n: np.array([r[0][f"a_arm_{n}_z"] for r in rows]) for n in NAMES}
    y = {n: np.array([r[0][f"a_arm_{n}_y"] for r in rows]) for n in NAMES}
    x = {n: np.array([r[0][f"a_arm_{n}_x"] for r in rows]) for n in NAMES}
    a_b = np.array([r[1] for r in rows])
    th0, w0, th1, w1 = (np.array([r[i] for r in rows]) for i in range(2, 6))
    scale = np.sqrt(np.mean(z["loc1"] ** 2))
    for n in NAMES:
        r = geo.BUILTIN.arm_accel_points[n][1]  # distance from the pivot axis (the arm frame's x)
        # the point's velocity from the joint: v_z = v_b + omega r cos(theta),
        # v_y = -omega r sin(theta); its difference quotient over the substep (to 1e-4 of
        # Loc1's RMS: PyBullet's link and joint velocities differ by ~2e-5 of it)
        exp_z = a_b + r * (w1 * np.cos(th1) - w0 * np.cos(th0)) / DT
        exp_y = -r * (w1 * np.sin(th1) - w0 * np.sin(th0)) / DT
        assert np.max(np.abs(z[n] - exp_z)) < 1e-4 * scale
        assert np.max(np.abs(y[n] - exp_y)) < 1e-4 * scale
        assert np.max(np.abs(x[n])) < 1e-4 * scale  # the arm turns about x; the body heaves
    rms = {n: float(np.sqrt(np.mean(z[n] ** 2))) for n in NAMES}
    assert rms["loc1"] > rms["cg"] > rms["loc2"]
    assert rms["loc1"] > 10.0  # the bump moves the arm (m/s^2)
    # relative to the pivot, z scales with r: (a_loc1 - a_b) / (a_cg - a_b) = r_loc1 / r_cg
    rel1, relcg = z["loc1"] - a_b, z["cg"] - a_b
    big = np.abs(relcg) > 0.2 * np.max(np.abs(relcg))
    ratio = geo.BUILTIN.arm_accel_points["loc1"][1] / geo.BUILTIN.arm_accel_points["cg"][1]
    np.testing.assert_allclose(rel1[big] / relcg[big], ratio, rtol=0.02)


def test_the_plant_node_publishes_them(tmp_path: Path):
    out = tmp_path / "run"
    res = suscosim("run", str(ROOT / "scenarios" / "ch4_qvm_realistic_bump_pothole.toml"),
                   "--out", str(out), "--mode", "monolithic", "--quiet",
                   "--set", "run.t_end=0.6", "--set", "fatigue.live=false")
    assert res.returncode == 0, res.stderr + res.stdout
    assert json.loads((out / "summary.json").read_text())["status"] == "ok"
    table = read_table(out / "table.parquet")
    z = {n: np.asarray(table[f"plant/response/a_arm_{n}_z"], dtype=float) for n in NAMES}
    a_b = np.asarray(table["plant/response/a_b"], dtype=float)
    assert max(np.max(np.abs(z[n][:20])) for n in NAMES) < 1e-3  # at rest before the bump
    rms = {n: float(np.sqrt(np.mean(z[n] ** 2))) for n in NAMES}
    assert rms["loc1"] > rms["cg"] > rms["loc2"]
    # Loc2, 20 mm from the pivot axis, moves nearly with the body; Loc1 (274 mm) with the hub
    rel = {n: float(np.sqrt(np.mean((z[n] - a_b) ** 2))) for n in ("loc1", "loc2")}
    ratio = rel["loc2"] / rel["loc1"]
    assert abs(ratio - 0.020 / 0.274) < 0.01
