"""The coupling's energy residual: how wrong a run is because of its communication step.

After the energy-conservation idea of ECCO (Sadjina et al., "Energy conservation and power
bonds in co-simulations", arXiv 1602.06434; worked on a quarter car in arXiv 2406.17353): a
force exchanged between two nodes and the velocity it acts through form a *power bond*. The
force node computes F from the plant's state; between two exchanges the plant applies its own
version of that force (held, extrapolated or linearised: ``run.coupling``). The difference
between the force the plant applies at a step's end and the one the force node computes from
the state reached there, times the bond's velocity, is power one side sends and the other
does not receive:

    dE_k = h/2 [ (F_app(t_k+) - F(x_k)) v_k + (F_app(t_k+1-) - F(x_k+1)) v_k+1 ]     [J]

(the trapezoidal rule over step k; zero first term in the sequential exchange). It needs only
the run's table: no reference solution nor vehicle model. Two bonds, summed over corners:
``damper``, F_d [N] through the strut velocity v_rel = v_w - v_b [m/s]; ``tyre``, the vertical
tyre force F_t [N] through the wheel's vertical velocity v_w [m/s].

The relative residual of a bond is sum_k |dE_k| over the energy the bond carried,
sum_k h |F(x_k) v_k|; the totals go into ``summary.json`` as ``coupling_energy_residual``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

WARNING_THRESHOLD = 0.003
"""A total relative residual above this (0.3 %) is said after the run and in the report:
through the Chapter 3 study's factor of ~3.5 between the held forces' peak error and their
residual, it is about 1 % peak error (docs/coupling_residual.md)."""


@dataclass(frozen=True)
class BondResidual:
    """One power bond's residual over a run: ``dE`` per step [J] summed over corners (steps
    k = lag .. n - 2 - lag), ``abs_residual`` = sum |dE| [J], ``carried`` = sum h |F v| [J]."""

    dE: np.ndarray
    abs_residual: float
    carried: float

    @property
    def relative(self) -> float:
        """abs_residual / carried (0 for a bond that carried nothing)."""
        return self.abs_residual / self.carried if self.carried > 0 else 0.0


def _columns(table: Mapping[str, np.ndarray], name: str) -> np.ndarray:
    """The column ``name`` (or ``name[0]``, ``name[1]`` ...) as (n_steps, n_corners)."""
    if name in table:
        return np.asarray(table[name], dtype=np.float64)[:, None]
    cols: list[np.ndarray] = []
    while f"{name}[{len(cols)}]" in table:
        cols.append(np.asarray(table[f"{name}[{len(cols)}]"], dtype=np.float64))
    if not cols:
        raise KeyError(name)
    return np.stack(cols, axis=1)


def applied_force(coupling: str, F: np.ndarray, dFdx: np.ndarray, x_seen: np.ndarray,
                  x_now: np.ndarray, F_before: np.ndarray, r: float | np.ndarray, clip: bool,
                  sign: float) -> np.ndarray:
    """The force the plant applies within a step (as ``nodes/plant/coupling.py``): ``F`` the
    step's force [N], ``dFdx`` its derivative (k_t [N/m] or c_eff [N s/m]) about ``x_seen``
    (z_w [m] or v_rel [m/s]), ``x_now`` that variable now, ``F_before`` the previous step's
    force [N], ``r`` time into the step over h; ``clip``: F >= 0 (tyre); ``sign`` -1: F falls
    with x (tyre: F_t = F_t,k - k_t (z_w - z_w,k))."""
    if coupling == "hold":
        out = F
    elif coupling == "linear":
        out = F + (F - F_before) * r
    elif coupling == "jacobian":
        out = F + sign * dFdx * (x_now - x_seen)
    else:
        raise ValueError(f"unknown coupling {coupling!r}")
    return np.maximum(0.0, out) if clip else out


def coupling_residual(table: Mapping[str, np.ndarray], h: float, coupling: str,
                      exchange: str) -> dict[str, BondResidual]:
    """Both bonds' residuals of a run's whole table (one block of
    :class:`cosim.coupling_stream.ResidualStream`; a bond whose columns it lacks left out)."""
    from .coupling_stream import ResidualStream

    try:
        _columns(table, "plant/state/v_w"), _columns(table, "plant/state/v_b")
    except KeyError:
        return {}
    stream = ResidualStream(h, coupling, exchange)
    dE = stream.feed(table)
    return {name: BondResidual(dE[name], r.abs_residual, r.carried)
            for name, r in stream.result().items()}


def summary(residuals: Mapping[str, BondResidual]) -> dict[str, float]:
    """``summary.json``'s ``coupling_energy_residual``: each bond's relative residual, total."""
    out = {name: r.relative for name, r in residuals.items()}
    carried = sum(r.carried for r in residuals.values())
    out["total"] = (sum(r.abs_residual for r in residuals.values()) / carried
                    if carried > 0 else 0.0)
    return out
