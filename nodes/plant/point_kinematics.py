"""Points fixed to a rigid link, in plain floats: where they are and how fast they move.

The double-wishbone corner (:mod:`nodes.plant.double_wishbone`) reads its hardpoints this way
every substep: elementwise sums and products in Python floats (a few 3-vectors a call, where
numpy's per-call overhead was most of the cost), the 3x3 rotation left to numpy (OpenBLAS uses
fused multiply-adds there, which Python floats cannot reproduce bit for bit). Vectors [m],
velocities [m/s], angular velocities [rad/s], in the world frame.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def world_point(pos: Sequence[float], R: np.ndarray, local: np.ndarray) -> list[float]:
    """World position of a point fixed to a link whose frame is at ``pos`` with rotation
    ``R`` (getLinkState's [4], and [5] as a matrix), at ``local`` in that frame [m]:
    pos + R @ local (the rotation a numpy product, the sum in floats)."""
    w = (R @ local).tolist()
    return [pos[0] + w[0], pos[1] + w[1], pos[2] + w[2]]


def point_velocity(link_state: Sequence[Sequence[float]], point: Sequence[float]) -> list[float]:
    """World velocity of a point fixed to a link (``link_state`` with velocity and forward
    kinematics): v_com + omega x (r - r_com) [m/s], in floats."""
    v, w, com = link_state[6], link_state[7], link_state[0]
    c = cross3(w, (point[0] - com[0], point[1] - com[1], point[2] - com[2]))
    return [v[0] + c[0], v[1] + c[1], v[2] + c[2]]


def cross3(a: Sequence[float] | np.ndarray, b: Sequence[float] | np.ndarray) -> list[float]:
    """a x b of two 3-vectors, in floats: the same products and differences as ``np.cross``
    (so the same bits), without its array handling (~20 us a call, 11 calls a step)."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return [a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0]
