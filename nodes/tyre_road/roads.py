"""Road profiles: discrete events (step, ramp, bump, pothole) and the common `Road` interface.

A road gives the vertical height z_g [m] of the road surface, up positive, for the **left**
(track 0) and **right** (track 1) wheel paths, at arrays of distance s [m] travelled along the
road. Heights are relative to the flat road the vehicle stands on at t = 0 (so they are also the
tyre-base displacements from static equilibrium, z_g in Eq. 3.1). Before the road starts (s < 0,
e.g. a rear wheel that has not reached s = 0 yet) the road is flat: z_g = 0.

The road is driven at a constant forward speed v [m/s] (thesis Ch. 4: 34 km/h = 9.44 m/s); a
point at longitudinal offset x_i from the front axle reaches distance s_i(t) = v t + x_i (see
:mod:`nodes.tyre_road.wheel_paths`). Length L and speed give the run's duration L / v.

Event shapes (s measured from the event start x_0, event length l, height h):

* step:    z = h for s >= x_0 (Ch. 3: 20 mm).
* ramp:    z rises linearly from 0 to h over l, then stays at h.
* bump:    z = h/2 (1 - cos(2 pi (s - x_0)/l)) over l (a "1 - cos" bump, Blundell & Harty style).
* pothole: the same shape downwards with depth d > 0 (``shape = "cosine"``), or a sharp-edged
  rectangular hole (``shape = "rect"``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

KMH = 1.0 / 3.6
"""1 km/h in m/s."""


@dataclass(kw_only=True)
class Road:
    """A road under two wheel tracks (0 left, 1 right) at constant ``speed`` v [m/s]; ``length``
    L [m] or None; ``corners``: the corner names that see it (the others a flat road; thesis
    Ch. 4 excites only FR), None for all; ``name`` ("events", "pave", "csv:FILE" ...)."""

    speed: float = 0.0
    length: float | None = None
    corners: tuple[str, ...] | None = None
    name: str = "road"

    def height(self, s: np.ndarray, track: int) -> np.ndarray:
        """Road height z_g [m] at distances ``s`` [m] on ``track`` (0 left, 1 right)."""
        raise NotImplementedError

    @property
    def duration_s(self) -> float | None:
        """Run duration L / v [s] when length and speed are both given."""
        if self.length is None or self.speed <= 0:
            return None
        return self.length / self.speed


def _check_track(track: int) -> None:
    if track not in (0, 1):
        raise ValueError(f"track must be 0 (left) or 1 (right), got {track!r}")


def step_height(s: np.ndarray, x_start: float, height: float) -> np.ndarray:
    """Step of ``height`` [m] at distance ``x_start`` [m]."""
    s = np.asarray(s, dtype=float)
    return np.where(s >= x_start, height, 0.0)


def ramp_height(s: np.ndarray, x_start: float, height: float, length: float) -> np.ndarray:
    """Linear ramp from 0 to ``height`` [m] over ``length`` [m] starting at ``x_start``."""
    s = np.asarray(s, dtype=float)
    u = np.clip((s - x_start) / length, 0.0, 1.0)
    return height * u


def bump_height(s: np.ndarray, x_start: float, height: float, length: float) -> np.ndarray:
    """"1 - cos" bump of peak ``height`` [m] and base ``length`` [m] starting at ``x_start``."""
    s = np.asarray(s, dtype=float)
    u = (s - x_start) / length
    inside = (u >= 0.0) & (u <= 1.0)
    return np.where(inside, 0.5 * height * (1.0 - np.cos(2.0 * np.pi * u)), 0.0)


def pothole_height(s: np.ndarray, x_start: float, depth: float, length: float,
                   shape: str = "cosine") -> np.ndarray:
    """Pothole of ``depth`` [m] (> 0, downwards) and ``length`` [m] from ``x_start``: ``shape``
    "cosine" (1 - cos dip) or "rect" (sharp edges, flat bottom)."""
    s = np.asarray(s, dtype=float)
    if shape == "cosine":
        return -bump_height(s, x_start, depth, length)
    if shape == "rect":
        inside = (s >= x_start) & (s < x_start + length)
        return np.where(inside, -depth, 0.0)
    raise ValueError(f"pothole shape must be 'cosine' or 'rect', got {shape!r}")


@dataclass(frozen=True)
class RoadEvent:
    """One event: ``kind`` step|ramp|bump|pothole on ``tracks``; ``height`` [m] (a pothole's
    depth, positive)."""

    kind: str
    x_start: float
    height: float
    length: float = 0.0
    shape: str = "cosine"
    tracks: tuple[int, ...] = (0, 1)

    def height_at(self, s: np.ndarray) -> np.ndarray:
        if self.kind == "pothole":
            return pothole_height(s, self.x_start, self.height, self.length, self.shape)
        if self.kind == "step":
            return step_height(s, self.x_start, self.height)
        shape = {"ramp": ramp_height, "bump": bump_height}[self.kind]
        return shape(s, self.x_start, self.height, self.length)


@dataclass
class EventRoad(Road):
    """A flat road carrying discrete events, superposed (heights add)."""

    events: Sequence[RoadEvent]
    name: str = field(default="events", kw_only=True)

    def height(self, s: np.ndarray, track: int) -> np.ndarray:
        _check_track(track)
        s = np.asarray(s, dtype=float)
        z = np.zeros(s.shape)
        for ev in self.events:
            if track in ev.tracks:
                z = z + ev.height_at(s)
        return z


@dataclass
class SampledRoad(Road):
    """A road known at samples: distances ``x`` [m] (increasing) and heights ``z_left``,
    ``z_right`` [m]; linear interpolation between samples; flat (0) for s < x[0], and the last
    height held for s > x[-1]."""

    x: np.ndarray
    z_left: np.ndarray
    z_right: np.ndarray
    name: str = field(default="sampled", kw_only=True)

    def height(self, s: np.ndarray, track: int) -> np.ndarray:
        _check_track(track)
        z = self.z_left if track == 0 else self.z_right
        s = np.asarray(s, dtype=float)
        return np.interp(s, self.x, z, left=0.0, right=float(z[-1]))
