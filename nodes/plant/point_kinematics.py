"""Points fixed to a rigid link, and small rotations, in plain floats.

The double-wishbone corner (:mod:`nodes.plant.double_wishbone`) reads its hardpoints this way
every substep: elementwise sums and products in Python floats (a few 3-vectors a call, where
numpy's per-call overhead was most of the cost). What feeds the dynamics keeps numpy's bits: a
row-major product ``R @ v`` stays numpy's (OpenBLAS computes fma(r2, v2, fma(r0, v0, r1 v1)),
which Python floats cannot reproduce; several points under one rotation are one batched
``np.matmul``, the same bits per point); ``R.T @ v``, a dot product and a cross product are
plain sums, left to right, as numpy's (:func:`transpose_times`, :func:`cross3`). The arm loads
(outputs only) rotate in floats (:func:`to_frame`): within an ulp or two of numpy's products.
Vectors [m], velocities [m/s], angular velocities [rad/s].
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def point_velocity(link_state: Sequence[Sequence[float]], point: Sequence[float]) -> list[float]:
    """World velocity of a point fixed to a link (``link_state`` with velocity and forward
    kinematics): v_com + omega x (r - r_com) [m/s], in floats (:func:`cross3`'s products)."""
    (v0, v1, v2), (w0, w1, w2), (c0, c1, c2) = link_state[6], link_state[7], link_state[0]
    r0, r1, r2 = point[0] - c0, point[1] - c1, point[2] - c2
    return [v0 + (w1 * r2 - w2 * r1), v1 + (w2 * r0 - w0 * r2), v2 + (w0 * r1 - w1 * r0)]


def cross3(a: Sequence[float] | np.ndarray, b: Sequence[float] | np.ndarray) -> list[float]:
    """a x b of two 3-vectors, in floats: the same products and differences as ``np.cross``
    (so the same bits), without its array handling (~20 us a call, 11 calls a step)."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return [a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0]


def transpose_times(R: Sequence[Sequence[float]], v: Sequence[float]) -> list[float]:
    """R.T @ v in floats for ``R`` given by its rows (``ndarray.tolist()``): the same bits as
    numpy's ``R.T @ v`` (tests/vehicles/test_double_wishbone_floats.py)."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R
    v0, v1, v2 = v
    # from +0.0, as OpenBLAS accumulates (a sum of -0.0 products is +0.0 there)
    return [0.0 + r00 * v0 + r10 * v1 + r20 * v2, 0.0 + r01 * v0 + r11 * v1 + r21 * v2,
            0.0 + r02 * v0 + r12 * v1 + r22 * v2]


def to_frame(R_f: Sequence[Sequence[float]], R_link: Sequence[float],
             v: Sequence[float]) -> list[float]:
    """R_f.T @ R_link.T @ v in floats: a world vector in a frame whose axes are ``R_f`` (by
    rows) in a link whose world rotation is ``R_link`` (row-major, 9 values, as
    ``getMatrixFromQuaternion`` gives it)."""
    return transpose_times(R_f, transpose_times((R_link[0:3], R_link[3:6], R_link[6:9]), v))
