"""Reference mode: the thesis's "purely mathematical" model (Simulink ode113, tolerance 1e-10):
Eq. 3.1 with the co-simulation's road, tyre and passive damper, by SciPy ``solve_ivp`` (DOP853)
restarted at every road discontinuity (a step input resolved exactly); a co-simulation table's
columns, so the two compare directly (Table 3.3).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from cosim.errors import ScenarioError
from cosim.table import Table, channel_stats, export
from nodes.plant.model import GRAVITY
from nodes.plant.quarter_car_lumped import LumpedQuarterCarParams
from nodes.tyre_road.config import build_road, build_tyre


def _params(scenario: dict[str, Any]) -> tuple[LumpedQuarterCarParams, float]:
    veh, ctl = scenario["vehicle"], scenario["controller"]
    if veh.get("model", "quarter_car_lumped") != "quarter_car_lumped":
        raise ScenarioError("vehicle.model", veh.get("model"),
                            "'quarter_car_lumped' (the reference mode solves the lumped model)")
    if ctl.get("law", "passive") != "passive":
        raise ScenarioError("controller.law", ctl.get("law"),
                            "'passive' (the reference mode has the linear passive damper)")
    fields = LumpedQuarterCarParams.__dataclass_fields__
    params = LumpedQuarterCarParams(**{k: float(v) for k, v in veh.items() if k in fields})
    return params, float(ctl.get("c", 1500.0))


def _breaks(road: Any, offsets: np.ndarray, t_end: float) -> list[float]:
    """Times at which the road input under any contact point has a kink or jump."""
    times = {0.0, t_end}
    for ev in getattr(road, "events", []):
        for x in (ev.x_start, ev.x_start + ev.length):
            for dx in offsets:
                if road.speed > 0:
                    times.add((x - dx) / road.speed)
    return sorted(t for t in times if 0.0 <= t <= t_end)


def reference_solution(scenario: dict[str, Any], t_eval: np.ndarray) -> Table:
    """The reference responses at times ``t_eval`` [s] (ascending), as a run table."""
    p, c_s = _params(scenario)
    road, tyre = build_road(scenario["road"]), build_tyre(scenario["tyre"])
    offsets = np.asarray(tyre.contact_offsets, dtype=float)
    W = np.array([(p.sprung_mass + p.unsprung_mass) * GRAVITY])
    track = 1

    def forces(t: float, z_b, z_w, v_b, v_w):
        z_g = road.height(road.speed * t + offsets, track)
        F_t, _ = tyre.force(np.atleast_1d(z_w), z_g[None, :], W)
        F_d = c_s * (v_w - v_b)
        F_s = p.spring_stiffness * (z_w - z_b)
        return float(F_t[0]), F_d, F_s, z_g

    def rhs(t: float, y: np.ndarray) -> list[float]:
        z_b, z_w, v_b, v_w = y
        F_t, F_d, F_s, _ = forces(t, z_b, z_w, v_b, v_w)
        return [v_b, v_w, (F_s + F_d) / p.sprung_mass, (F_t - W[0] - F_s - F_d) / p.unsprung_mass]

    rtol = float(scenario["run"].get("rtol", 1e-10))
    t_end = float(t_eval[-1])
    bps = _breaks(road, offsets, t_end)
    y = np.zeros(4)
    Y = np.zeros((4, len(t_eval)))
    for i, (a, b) in enumerate(zip(bps[:-1], bps[1:], strict=True)):
        if b <= a:
            continue
        sol = solve_ivp(rhs, (a, b), y, method="DOP853", rtol=rtol, atol=rtol * 1e-3,
                        dense_output=True)
        last = i == len(bps) - 2
        sel = (t_eval >= a) & ((t_eval < b) | (last & (t_eval <= b)))
        if sel.any():
            Y[:, sel] = sol.sol(t_eval[sel])
        y = sol.y[:, -1]
    out: Table = {"k": np.arange(len(t_eval)), "t": np.asarray(t_eval, dtype=float)}
    rows = [forces(t, *Y[:, j]) for j, t in enumerate(t_eval)]
    F_t = np.array([r[0] for r in rows])
    F_d = np.array([r[1] for r in rows])
    F_s = np.array([r[2] for r in rows])
    out["plant/state/z_b"], out["plant/state/z_w"] = Y[0], Y[1]
    out["plant/state/v_b"], out["plant/state/v_w"] = Y[2], Y[3]
    out["plant/response/a_b"] = (F_s + F_d) / p.sprung_mass
    out["plant/response/a_w"] = (F_t - W[0] - F_s - F_d) / p.unsprung_mass
    out["plant/response/F_t"], out["plant/response/F_d"] = F_t, F_d
    out["plant/response/F_s"] = F_s
    out["tyre_road/force/F_t"] = F_t
    out["tyre_road/force/z_g"] = np.array([r[3][np.argmin(np.abs(offsets))] for r in rows])
    out["controller/force/F_d"] = F_d
    return out


def run_reference(scenario: dict[str, Any], folder: Path) -> dict[str, Any]:
    """Solve on the communication grid t_k = k h, export the table, return its stats."""
    run = scenario["run"]
    t = np.arange(run["n_steps"] + 1) * run["h"]
    table = reference_solution(scenario, t)
    return {"stats": channel_stats(table), "files": export(table, folder), "rows": len(t)}
