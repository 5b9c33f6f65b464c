"""How the plant treats its force inputs between two communication steps (pure numerics).

The thesis holds the forces of step k constant until t_{k+1} (zero-order hold). That error
grows with the step h and is what Table 3.3 measures. Two better options:

* ``linear``: extrapolate each force from its last two values, F(t_k + s) = F_k +
  (F_k - F_{k-1}) s / h. Second order on smooth inputs, but it overshoots at a discontinuity
  (a road step): one step later it has added the jump a second time.
* ``jacobian``: the force nodes also send the local derivative of their force with respect
  to the plant's state (tyre: k_t = dF_t/d(z_g - z_w); damper: c_eff = dF_d/d(v_w - v_b)),
  and the plant applies the linearised force at every substep:
  F_t(s) = max(0, F_t,k - k_t (z_w(s) - z_w,k)),  F_d(s) = F_d,k + c_eff (v_rel(s) - v_rel,k).
  For a linear tyre and damper this is exact apart from the road input's change within the
  step; lift-off stays exact because the clip is applied at every substep.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

MODES = ("hold", "linear", "jacobian")


@dataclass
class StepInputs:
    """The forces of step k and what the coupling needs to vary them within the step."""

    F_t: np.ndarray
    F_d: np.ndarray
    k_t: np.ndarray
    c_eff: np.ndarray
    z_w: np.ndarray
    v_rel: np.ndarray


def substep_forces(mode: str, now: StepInputs, before: StepInputs | None, s: float, h: float,
                   state: Mapping[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(F_t, F_d) [N] to apply at t_k + s [s] within a step of h [s]: ``now`` the inputs of
    step k, ``before`` of step k-1 (None at k = 0), ``state`` the plant's now (``jacobian``
    reads its z_w [m] and v_w - v_b [m/s])."""
    if mode == "hold" or (mode == "linear" and before is None):
        return now.F_t, now.F_d
    if mode == "linear" and before is not None:
        r = s / h
        F_t = np.maximum(0.0, now.F_t + (now.F_t - before.F_t) * r)
        return F_t, now.F_d + (now.F_d - before.F_d) * r
    if mode == "jacobian":
        F_t = np.maximum(0.0, now.F_t - now.k_t * (state["z_w"] - now.z_w))
        return F_t, now.F_d + now.c_eff * (state["v_w"] - state["v_b"] - now.v_rel)
    raise ValueError(f"unknown coupling mode {mode!r}; expected one of {MODES}")
