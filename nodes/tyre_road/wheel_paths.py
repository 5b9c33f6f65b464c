"""Wheel paths: where on the road each tyre contact point is (docs/vehicles_roads.md).

From the plant's ``info()`` per corner: ``wheel_x`` [m], the wheel centre's offset from the
front axle (x forward: 0 front, -wheelbase rear), ``wheel_track`` (0 left, 1 right) and
``corner_names``. Contact point j of corner i (tyre offset dx_j,
:attr:`Tyre.contact_offsets`) is at distance s_ij(t) = v t + wheel_x[i] + dx_j on its track,
so a rear wheel sees what the front wheel saw wheelbase / v earlier (thesis Eq. 4.11) and a
flat road while s < 0. A vehicle that moves itself (the four-corner vehicle) gives its wheel
centres' world (x, y) instead, read at their stations along the path its driver follows
(:class:`RoadPath`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .roads import Road


def road_heights(road: Road, t: float, wheel_x: Sequence[float], wheel_track: Sequence[int],
                 contact_offsets: np.ndarray | None = None,
                 corner_names: Sequence[str] | None = None) -> np.ndarray:
    """Road heights z_g [m] under every contact point at time ``t`` [s], shape (n_corners,
    n_points): :func:`road_heights_at` the stations ``v t + wheel_x`` [m]."""
    return road_heights_at(road, road.speed * t + np.asarray(wheel_x, dtype=float),
                           wheel_track, contact_offsets, corner_names)


def road_heights_at(road: Road, s: np.ndarray, wheel_track: Sequence[int],
                    contact_offsets: np.ndarray | None = None,
                    corner_names: Sequence[str] | None = None) -> np.ndarray:
    """Road heights z_g [m] of shape (n_corners, n_points) for wheels whose contact centres
    are at stations ``s`` [m] along the road (a vehicle that moves itself, the four-corner
    vehicle: s from :meth:`RoadPath.station` of its wheel centres); the corners the road does
    not name see a flat road."""
    offs = np.zeros(1) if contact_offsets is None else np.asarray(contact_offsets, dtype=float)
    d = np.asarray(s, dtype=float)[:, None] + offs[None, :]
    z = np.zeros(d.shape)
    for i, track in enumerate(wheel_track):
        if road.corners is None or corner_names is None or corner_names[i] in road.corners:
            z[i] = road.height(d[i], int(track))
    return z


@dataclass(frozen=True)
class RoadPath:
    """The line a road's profile is laid along, in the world's x-y plane (module docstring).

    ``origin`` (x_0, y_0) [m]: where the line starts (the front axle's centre at t = 0), heading
    +x; ``radius`` R [m]: a circle, + left (centre at (x_0, y_0 + R)), - right, or None: the
    straight line y = y_0.
    """

    origin: tuple[float, float]
    radius: float | None = None

    def station(self, x: np.ndarray, y: np.ndarray, near: np.ndarray | None = None
                ) -> np.ndarray:
        """Station u [m] (arc length along the line of the foot of each point (x, y) [m]).

        Straight: u = x - x_0. Circle: u = R (a - a_0), a the point's polar angle about the
        centre and a_0 = -sign(R) pi / 2 the origin's; of the values u + 2 pi |R| n the one
        nearest ``near`` (the previous stations; None: x - x_0) is taken, so that u grows
        past a lap and a point behind the origin gets u < 0.
        """
        x = np.asarray(x, dtype=float)
        u_straight = x - self.origin[0]
        if self.radius is None:
            return u_straight
        R = self.radius
        a = np.arctan2(np.asarray(y, dtype=float) - (self.origin[1] + R), u_straight)
        u = R * (a + np.sign(R) * np.pi / 2)
        lap = 2 * np.pi * abs(R)
        ref = u_straight if near is None else np.asarray(near, dtype=float)
        return u + lap * np.round((ref - u) / lap)


def driver_radius(vehicle: Mapping[str, Any]) -> float | None:
    """The circle's radius R [m] the scenario's driver follows (``vehicle.driver.radius``),
    or None (no driver, or an open-loop steer: the road is laid straight along +x)."""
    driver = vehicle.get("driver") or {}
    r = driver.get("radius")
    return None if r is None else float(r)
