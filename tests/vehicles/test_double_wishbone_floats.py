"""The double-wishbone corner's float helpers give the same bits as the numpy expressions they
replaced (issue #16: the speed work must not move the simulated numbers)."""

from __future__ import annotations

import numpy as np

from nodes.plant import double_wishbone as dw
from nodes.plant import double_wishbone_geometry as geo
from nodes.plant import point_kinematics as pk
from nodes.plant.arm_loads import arm_loads


def _vectors(n: int, seed: int) -> np.ndarray:
    """Random 3-vectors over many magnitudes, with zeros, signed zeros and tiny values."""
    rng = np.random.default_rng(seed)
    v = rng.standard_normal((n, 3)) * 10.0 ** rng.integers(-8, 6, size=(n, 1))
    v[::7, 1] = 0.0
    v[::11, 2] = -0.0
    v[::13, 0] = 1e-300
    return v


def _bits(x) -> bytes:
    return np.asarray(x, dtype=float).tobytes()


def test_cross3_is_np_cross_bit_for_bit():
    a, b = _vectors(2000, 1), _vectors(2000, 2)
    for x, y in zip(a, b, strict=True):
        assert _bits(pk.cross3(x.tolist(), y.tolist())) == _bits(np.cross(x, y))
        assert _bits(pk.cross3(x, y)) == _bits(np.cross(x, y))  # arrays in: the same


def test_point_velocity_is_the_numpy_expression_bit_for_bit():
    v, w, com, r = (_vectors(1000, s) for s in (3, 4, 5, 6))
    for i in range(len(v)):
        state = (tuple(com[i]), None, None, None, None, None, tuple(v[i]), tuple(w[i]))
        want = v[i] + np.cross(w[i], r[i] - com[i])
        assert _bits(pk.point_velocity(state, r[i].tolist())) == _bits(want)


def test_transpose_times_is_numpy_bit_for_bit():
    R, v = _vectors(1500, 10), _vectors(500, 11)
    for i in range(len(v)):
        M = R[3 * i:3 * i + 3]
        assert _bits(pk.transpose_times(M.tolist(), v[i].tolist())) == _bits(M.T @ v[i])


def test_batched_rotation_is_each_product_bit_for_bit():
    """The corner rotates its arm points in one ``np.matmul``: each point's bits are those of
    ``R @ p`` alone (what the dynamics read)."""
    rng = np.random.default_rng(12)
    for _ in range(300):
        q = rng.standard_normal(4)
        R = np.array(dw.p.getMatrixFromQuaternion((q / np.linalg.norm(q)).tolist())).reshape(3, 3)
        pts = _vectors(5, int(rng.integers(1 << 30)))
        got = np.matmul(R, pts.reshape(-1, 3, 1)).reshape(-1, 3)
        for k in range(5):
            assert _bits(got[k]) == _bits(R @ pts[k])


def test_to_frame_is_the_numpy_product_within_an_ulp():
    """The arm loads' rotation in floats: numpy's products use fused multiply-adds, so a few
    ulps of the vector's size apart, never more."""
    rng = np.random.default_rng(13)
    for v in rng.standard_normal((500, 3)) * 10.0 ** rng.integers(-3, 6, size=(500, 1)):
        Rf, Rl = (np.linalg.qr(rng.standard_normal((3, 3)))[0] for _ in range(2))
        want = Rf.T @ Rl.T @ v
        got = pk.to_frame(Rf.tolist(), Rl.ravel().tolist(), v.tolist())
        assert np.abs(np.array(got) - want).max() <= 4e-16 * np.linalg.norm(v)


def _arm_loads_numpy(model: dw.DoubleWishboneCorner) -> dict[str, float]:
    """arm_loads as it was written with small arrays (before issue #16's floats)."""
    c, b = model.client, model.body
    R_af = geo.BUILTIN.arm_rotation
    R_arm, hub_quat, u_list = model._applied_pose
    R_hub = np.array(dw.p.getMatrixFromQuaternion(hub_quat)).reshape(3, 3)
    u = np.array(u_list)
    to_arm = R_af.T @ R_arm.T
    w_pivot = np.array(dw.p.getJointState(b, dw.LOWER_ARM, physicsClientId=c)[2])
    F_link = w_pivot[:3]
    M_link = w_pivot[3:] + np.cross(model._arm_r_com, F_link)
    F, M = R_af.T @ F_link, R_af.T @ M_link
    d = geo.BUILTIN.bush_spacing
    front = np.array([F[0] / 2, F[1] / 2 + M[2] / d, F[2] / 2 - M[1] / d])
    rear = np.array([F[0] / 2, F[1] / 2 - M[2] / d, F[2] / 2 + M[1] / d])
    w_bj = np.array(dw.p.getJointStateMultiDof(b, dw.HUB, physicsClientId=c)[2])
    ball = to_arm @ (-(R_hub @ w_bj[:3]))
    damper = to_arm @ (-model._F_d * u)
    bump = to_arm @ np.array([0.0, 0.0, -model._F_bs])
    out = {}
    for name, f in (("ball_joint", ball), ("damper_mount", damper), ("bush_front", front),
                    ("bush_rear", rear)):
        for axis, v in zip("xyz", f, strict=True):
            out[f"{name}_{axis}"] = float(v)
    out["bump_stop_y"], out["bump_stop_z"] = float(bump[1]), float(bump[2])
    out["torsion_bar_mx"] = float(M[0])
    return out


def _rates_numpy(model: dw.DoubleWishboneCorner) -> dict[str, float]:
    """response_velocities as it was written with small arrays."""
    arm = model._arm_state
    pos, R = np.array(arm[4]), model._R_arm
    o = 0.5 * (geo.BUILTIN.lower_bush_front + geo.BUILTIN.lower_bush_rear)  # the arm link's origin
    out = {}
    for name, pt in geo.BUILTIN.arm_accel_points.items():
        r = pos + R @ dw._link_point(o, dw.la.to_corner(pt))
        v = np.array(arm[6]) + np.cross(np.array(arm[7]), r - np.array(arm[0]))
        for axis, val in zip("xyz", v, strict=True):
            out[f"a_arm_{name}_{axis}"] = float(val)
    return out


def test_arm_loads_and_rates_are_the_array_versions():
    """Through a stroke into the bumper and back (F_bs > 0 on the way): every arm-point
    velocity the floats give is the array code's, bit for bit; every arm load within 1e-15
    of the largest (the floats' rotations, test_to_frame_is_the_numpy_product_within_an_ulp)."""
    m = dw.DoubleWishboneCorner()
    try:
        W = m.static_tyre_load()
        bumped = 0
        for i in range(600):
            F_t = W * (1.0 + 2.5 * np.sin(np.pi * i / 300.0) ** 2)
            m.substep(2.5e-4, F_t, np.array([800.0 * np.cos(i / 40.0)]))
            bumped += m._F_bs > 0.0
            got, want = arm_loads(m), _arm_loads_numpy(m)
            assert got.keys() == want.keys()
            g, w = np.array(list(got.values())), np.array(list(want.values()))
            assert np.abs(g - w).max() <= 1e-15 * np.abs(w).max(), i
            rates = m.response_velocities()
            assert _bits(list(rates.values())) == _bits(list(_rates_numpy(m).values())), i
        assert bumped > 10  # the bumper path was taken
    finally:
        m.close()


def test_floats_keep_the_arm_loads_and_response_types():
    """What the node takes from the model keeps its types: floats for the response rates and
    the arm loads (the wire encodes a float and a length-1 array the same)."""
    m = dw.DoubleWishboneCorner()
    try:
        m.substep(2.5e-4, m.static_tyre_load() * 1.5, np.array([300.0]))
        loads = arm_loads(m)
        assert all(type(v) is float for v in loads.values())
        assert len(loads) == 15
        rates = m.response_velocities()
        assert len(rates) == 9
        assert all(type(v) is float for v in rates.values())
    finally:
        m.close()
