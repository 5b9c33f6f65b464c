"""The adaptive communication step (``run.h = "auto"``): ECCO's power-bond
error estimate and its PI step-size controller (Sadjina et al., arXiv 1602.06434, Sec. 4;
the same structure as libcosim's ``ecco_algorithm``). Pure numerics, no I/O.

After step k (length h_k) the plant knows, for each power bond (damper force through the
strut velocity, tyre force through the wheel's vertical velocity; :mod:`cosim.coupling_energy`),
the force it applied at the end of the step and the force the force node computed from the
state it reached there. Their difference times the bond's velocity, over the step, is the
energy the coupling created or lost (the sequential exchange: the trapezoid's first half is
zero, the plant starting each step from the force of its own state):

    dE_k = h_k / 2 * sum_bonds (F_app(t_k+1-) - F(x_k+1)) v_k+1               [J]
    E_k  = h_k * sum_bonds |F(x_k+1) v_k+1|                                     [J]
    eps_k = |dE_k| / (atol + tol * E_k)                                         [-]

``eps = 1`` is the step the user asked for (``run.h_tol``: dE relative to the energy the bonds
carry over the step; ``atol`` keeps a bond at rest from asking for ever smaller steps). The
next step, a PI controller on log(eps) (Gustafsson's, as ECCO):

    h_k+1 = h_k * clip(safety * eps_k^-(kI + kP) * eps_k-1^kP, min_change, max_change)

clipped to [h_min, h_max], and shortened so that the run ends exactly at t_end (a last step
shorter than h_min / 2 is merged into the one before).

The gains are ours (ECCO leaves them to the user): kI = 0.3 and kP = 0.1 on an error that is
first order in h for the held forces; the safety factor 0.9 and the change bounds
[0.5, 1.5] keep the step from chattering at a road event. Checked in docs/coupling_residual.md
("Adaptive step") against the reference solution on the bump and pothole.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class AdaptiveStep:
    """The step-size controller's settings (``run.h_min``, ``run.h_max``, ``run.h_tol``)."""

    h_min: float  # smallest step [s]
    h_max: float  # largest step [s]
    tol: float  # energy residual allowed per step, over the energy carried over it [-]
    atol: float = 1e-6  # absolute floor of the energy residual's scale [J]
    safety: float = 0.9
    k_i: float = 0.3
    k_p: float = 0.1
    min_change: float = 0.5
    max_change: float = 1.5

    def __post_init__(self) -> None:
        if not 0 < self.h_min < self.h_max:
            raise ValueError(f"h_min = {self.h_min!r} s, h_max = {self.h_max!r} s: "
                             "0 < h_min < h_max")
        if not self.tol > 0 or not self.atol > 0:
            raise ValueError(f"tol = {self.tol!r}, atol = {self.atol!r}: both > 0")

    @classmethod
    def of_run(cls, run: dict[str, Any]) -> AdaptiveStep | None:
        """The controller of a resolved ``[run]`` table, None for a fixed step."""
        if not run.get("adaptive"):
            return None
        return cls(float(run["h_min"]), float(run["h_max"]), float(run["h_tol"]))

    @property
    def first(self) -> float:
        """The first step [s]: the smallest (nothing is known of the coupling yet)."""
        return self.h_min

    def error(self, dE: float, carried: float) -> float:
        """eps_k of a step whose bonds' residual is ``dE`` [J] and energy ``carried`` [J]."""
        return abs(dE) / (self.atol + self.tol * abs(carried))

    def next(self, h: float, eps: float, eps_prev: float | None) -> float:
        """h_k+1 [s] from h_k = ``h`` [s] and the errors of steps k and k - 1."""
        if eps <= 0.0 or not math.isfinite(eps):
            gain = self.max_change if eps == 0.0 else self.min_change
        else:
            gain = self.safety * eps ** -(self.k_i + self.k_p)
            if eps_prev is not None and eps_prev > 0.0:
                gain *= eps_prev ** self.k_p
            gain = min(max(gain, self.min_change), self.max_change)
        return min(max(h * gain, self.h_min), self.h_max)

    def clamp_to_end(self, h: float, t: float, t_end: float) -> float:
        """``h`` shortened so that the run ends at ``t_end`` [s] (no last step shorter than
        h_min / 2: it joins the step before)."""
        left = t_end - t
        if h >= left - 0.5 * self.h_min:
            return left
        return h

    def is_last(self, t: float, t_end: float) -> bool:
        """Whether the step at ``t`` [s] is the run's last (t_N = t_end, within h_min / 2)."""
        return t >= t_end - 0.5 * self.h_min


def step_residual(F_app_t: np.ndarray, F_t: np.ndarray, v_w: np.ndarray,
                  F_app_d: np.ndarray, F_d: np.ndarray, v_rel: np.ndarray,
                  h: float) -> tuple[float, float]:
    """(dE_k [J], E_k [J]) of one step of the sequential exchange, both bonds summed over
    corners: the applied forces at the step's end ``F_app_*`` [N], the forces computed from
    the end state ``F_t``, ``F_d`` [N], the bonds' velocities there ``v_w``, ``v_rel`` [m/s],
    the step ``h`` [s] (module docstring)."""
    dE = 0.5 * h * float(np.sum((F_app_t - F_t) * v_w) + np.sum((F_app_d - F_d) * v_rel))
    carried = h * float(np.sum(np.abs(F_t * v_w)) + np.sum(np.abs(F_d * v_rel)))
    return dE, carried
