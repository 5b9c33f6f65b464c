"""Wheel paths: where on the road each tyre contact point is at time t.

The plant's ``info()`` gives, per corner (order FL, FR, RL, RR, or one corner):

* ``wheel_x``  [m]: longitudinal offset of the wheel centre from the front axle, x forward
  (0 for front wheels, -wheelbase for rear wheels);
* ``wheel_track``: 0 for a left wheel, 1 for a right wheel;
* ``corner_names``: e.g. ["FL", "FR", "RL", "RR"] (["FR"] for a quarter car).

At time t the vehicle's front axle has travelled v t, so contact point j of corner i (tyre
offset dx_j, from :attr:`Tyre.contact_offsets`) is at distance

    s_ij(t) = v t + wheel_x[i] + dx_j

on track ``wheel_track[i]``. A rear wheel therefore sees what the front wheel on its track saw
a time wheelbase / v earlier (thesis Eq. 4.11, t_d = d_wb / v), and sees a flat road while
s < 0. If the road names ``corners``, the corners not named see a flat road.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .roads import Road


def contact_distances(t: float, speed: float, wheel_x: Sequence[float],
                      contact_offsets: np.ndarray) -> np.ndarray:
    """Distances s [m] of shape (n_corners, n_points) along the road at time ``t`` [s]."""
    return speed * t + np.asarray(wheel_x, dtype=float)[:, None] + \
        np.asarray(contact_offsets, dtype=float)[None, :]


def road_heights(road: Road, t: float, wheel_x: Sequence[float], wheel_track: Sequence[int],
                 contact_offsets: np.ndarray | None = None,
                 corner_names: Sequence[str] | None = None) -> np.ndarray:
    """Road heights z_g [m] under every contact point, shape (n_corners, n_points)."""
    if contact_offsets is None:
        contact_offsets = np.zeros(1)
    s = contact_distances(t, road.speed, wheel_x, contact_offsets)
    z = np.zeros(s.shape)
    for i, track in enumerate(wheel_track):
        if road.corners is not None and corner_names is not None \
                and corner_names[i] not in road.corners:
            continue
        z[i] = road.height(s[i], int(track))
    return z


def road_heights_at(road: Road, s: np.ndarray, wheel_track: Sequence[int],
                    contact_offsets: np.ndarray | None = None,
                    corner_names: Sequence[str] | None = None) -> np.ndarray:
    """Road heights z_g [m] of shape (n_corners, n_points) for wheels whose contact centres
    are at distances ``s`` [m] along the road (a vehicle that moves itself, the four-corner
    vehicle: s from its wheel centres' world x, not v t)."""
    offs = np.zeros(1) if contact_offsets is None else np.asarray(contact_offsets, dtype=float)
    d = np.asarray(s, dtype=float)[:, None] + offs[None, :]
    z = np.zeros(d.shape)
    for i, track in enumerate(wheel_track):
        if road.corners is not None and corner_names is not None \
                and corner_names[i] not in road.corners:
            continue
        z[i] = road.height(d[i], int(track))
    return z
