"""The whole-table coupling energy residual as it was computed before the streamed one
(:mod:`cosim.coupling_stream`), kept as the test oracle of the stream: the same trapezoid
over step k, written directly on the table's columns (docs of :mod:`cosim.coupling_energy`).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from cosim.coupling_energy import BondResidual, _columns, applied_force


def bond_residual(F: np.ndarray, dFdx: np.ndarray, x: np.ndarray, v: np.ndarray, h: float,
                  coupling: str, lag: int, clip: bool, sign: float) -> BondResidual:
    """Residual of one bond from its columns (rows = steps k = 0..n; columns = corners).

    ``F[k]``, ``dFdx[k]``: the force node's output of step k, computed from the plant's state
    of step k - lag (lag 0: sequential exchange, 1: parallel). ``x``: the plant variable the
    coupling linearises about (z_w or v_rel), ``v``: the bond's velocity [m/s], both per step.
    """
    n = F.shape[0]
    # steps k = lag .. n-2-lag: the force computed from the state at t_k is F[k + lag], and
    # the one from the state at t_k+1, F[k + 1 + lag], must be in the table
    m = n - 1 - 2 * lag
    if m <= 0:
        return BondResidual(np.zeros(0), 0.0, 0.0)
    k = np.arange(lag, lag + m)
    F_k, J_k = F[k], dFdx[k]
    F_prev = F[np.maximum(k - 1, 0)]
    seen = x[k - lag]
    true_start, true_end = F[k + lag], F[k + 1 + lag]
    app_start = applied_force(coupling, F_k, J_k, seen, x[k], F_prev, 0.0, clip, sign)
    app_end = applied_force(coupling, F_k, J_k, seen, x[k + 1], F_prev, 1.0, clip, sign)
    dE = 0.5 * h * ((app_start - true_start) * v[k] + (app_end - true_end) * v[k + 1])
    dE_step = dE.sum(axis=1)
    carried = float(h * np.abs(F[lag:n] * v[: n - lag]).sum())
    return BondResidual(dE_step, float(np.abs(dE).sum()), carried)


def coupling_residual(table: Mapping[str, np.ndarray], h: float, coupling: str,
                      exchange: str) -> dict[str, BondResidual]:
    """Both bonds' residuals from a run's table (columns as :mod:`cosim.table` names them).

    A bond whose columns the table lacks (no controller, a plant without a wheel) is left
    out. ``h`` [s] is the communication step.
    """
    lag = 0 if exchange == "sequential" else 1
    out: dict[str, BondResidual] = {}
    try:
        v_w = _columns(table, "plant/state/v_w")
        v_b = _columns(table, "plant/state/v_b")
    except KeyError:
        return out
    v_rel = v_w - v_b
    try:
        F_d = _columns(table, "controller/force/F_d")
        c_eff = _columns(table, "controller/force/c_eff")
        out["damper"] = bond_residual(F_d, c_eff, v_rel, v_rel, h, coupling, lag,
                                      clip=False, sign=1.0)
    except KeyError:
        pass
    try:
        F_t = _columns(table, "tyre_road/force/F_t")
        k_t = _columns(table, "tyre_road/force/k_t")
        z_w = _columns(table, "plant/state/z_w")
        out["tyre"] = bond_residual(F_t, k_t, z_w, v_w, h, coupling, lag, clip=True,
                                    sign=-1.0)
    except KeyError:
        pass
    return out
