"""Where the realistic corner meets its jounce bumper: the numbers of docs/vehicles_roads.md.

1. *First contact*, quasi-statically: a damper-axis tension ramp (2 kN/s, damped by
   30 000 N s/m on the damper's velocity, tyre on a flat road) pulls the suspension into
   jounce; the wheel travel relative to the body, z_w - z_b [m], and the arm angle [deg] at the
   first step with F_bs > 0.
2. *The Ch. 4 bump + pothole* (:func:`nodes.plant.equivalent_lumped.ch4_bump_pothole`, 34 km/h,
   3 s) with a linear damper of 3800 (the passive physical damper), 2000 and 1000 N s/m on the
   damper's velocity: peak jounce [m] and peak F_bs [N].
3. *A large bump*: 1-cos 100 mm x 1.0 m at 34 km/h, passive: peak jounce and peak F_bs.

Run: ``python -m orchestrator.studies.bump_stop [--dt 0.001] [--json]``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from nodes.tyre_road.roads import bump_height

from .double_wishbone import DoubleWishboneCorner, DoubleWishboneParams
from .equivalent_lumped import K_T, SPEED, ch4_bump_pothole


def first_contact(dt: float = 1e-3, params: DoubleWishboneParams | None = None
                  ) -> dict[str, float]:
    """Wheel travel ``jounce_m`` [m] and arm angle ``arm_angle_deg`` at the first bumper
    contact of a slow pull into jounce (module docstring, 1)."""
    m = DoubleWishboneCorner(params)
    W = m.static_tyre_load()
    try:
        for k in range(int(round(6.0 / dt))):
            st = m.state()
            if m.bump_stop_force() > 0.0:
                return {"jounce_m": float(st["z_w"][0] - st["z_b"][0]),
                        "arm_angle_deg": float(np.degrees(st["arm_angle"][0]))}
            F_t = np.maximum(0.0, W - K_T * st["z_w"])
            m.substep(dt, F_t, 30000.0 * st["v_damper"] - 2000.0 * k * dt)
    finally:
        m.close()
    raise RuntimeError("no bumper contact within the pull")


def road_run(z_g: Callable[[float], float], c: float, t_end: float = 3.0, dt: float = 1e-3,
             params: DoubleWishboneParams | None = None) -> dict[str, float]:
    """Peak jounce ``jounce_max_m`` [m] and peak bumper force ``F_bs_max`` [N] of the corner
    on the road z_g(t) [m] with a linear damper c [N s/m] on the damper's velocity."""
    m = DoubleWishboneCorner(params)
    W = m.static_tyre_load()
    rel, fbs = 0.0, 0.0
    try:
        for k in range(int(round(t_end / dt))):
            st = m.state()
            rel = max(rel, float(st["z_w"][0] - st["z_b"][0]))
            fbs = max(fbs, m.bump_stop_force())
            F_t = np.maximum(0.0, W + K_T * (z_g(k * dt) - st["z_w"]))
            m.substep(dt, F_t, c * st["v_damper"])
    finally:
        m.close()
    return {"jounce_max_m": rel, "F_bs_max": fbs}


def study(dt: float = 1e-3) -> dict[str, Any]:
    """Steps 1-3 of the module docstring: ``first_contact`` (:func:`first_contact`),
    ``ch4_bump_pothole`` (damping coefficient [N s/m] as text -> :func:`road_run`'s peaks)
    and ``bump_100mm`` (:func:`road_run`'s peaks)."""
    return {"first_contact": first_contact(dt),
            "ch4_bump_pothole": {
                str(int(c)): road_run(lambda t: float(ch4_bump_pothole(SPEED * t)), c, dt=dt)
                for c in (3800.0, 2000.0, 1000.0)},
            "bump_100mm": road_run(  # a 1-cos bump 100 mm x 1.0 m from x = 1 m
                lambda t: float(bump_height(np.asarray(SPEED * t), 1.0, 0.10, 1.0)), 3800.0,
                t_end=1.0, dt=dt)}
