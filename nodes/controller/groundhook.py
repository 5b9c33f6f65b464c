"""Groundhook laws (thesis Eq 2.4, Ahmadian [78]): damp the wheel against the ground.

The ideal groundhook force on the *wheel* is ``-c_gnd * v_w``; the wheel gets ``-F_d``, so the
demanded ``F_d = c_gnd * v_w``. It is dissipative when ``v_w * v_rel > 0``, i.e.
``-z_w' (z_b' - z_w') > 0`` in the thesis's notation.
"""

from __future__ import annotations

import numpy as np

from nodes.controller.dampers import semi_active_force, two_state_force
from nodes.controller.law_output import LawOutput, recording_c, recording_state
from nodes.controller.registry import HARD, SOFT, Param, control_law


def groundhook_condition(v_w: np.ndarray, v_rel: np.ndarray) -> np.ndarray:
    """True where the groundhook force is dissipative: ``v_w * v_rel > 0``."""
    return np.asarray(v_w, dtype=float) * np.asarray(v_rel, dtype=float) > 0.0


def groundhook_on_off(v_w: np.ndarray, v_rel: np.ndarray, c_soft: float, c_hard: float
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Two-state groundhook ``c = c_hard if v_w * v_rel > 0 else c_soft``, ``F_d = c v_rel``:
    (F_d in N, c in N·s/m, hard flag)."""
    hard = groundhook_condition(v_w, v_rel)
    return (*two_state_force(hard, v_rel, c_soft, c_hard), hard)


def groundhook_continuous(v_w: np.ndarray, v_rel: np.ndarray, c_gnd: float, c_min: float,
                          c_max: float) -> tuple[np.ndarray, np.ndarray]:
    """Continuous groundhook, demand ``F_d = c_gnd * v_w`` (gain in N·s/m, v_w the wheel's
    velocity in m/s) clipped to ``c_min..c_max`` (N·s/m): (F_d in N, c in N·s/m)."""
    return semi_active_force(c_gnd * np.asarray(v_w, dtype=float), v_rel, c_min, c_max)


# ------------------------------------------------------------------ the laws, by name


@control_law("groundhook_on_off")
def groundhook_on_off_law(v_w: np.ndarray, v_rel: np.ndarray, *, c_soft: float = SOFT,
                          c_hard: float = HARD) -> LawOutput:
    """Two-state groundhook: c_hard where v_w v_rel > 0, else c_soft (thesis Eq 2.4)."""
    return recording_state(*groundhook_on_off(v_w, v_rel, c_soft, c_hard))


@control_law("groundhook")
def groundhook_law(v_w: np.ndarray, v_rel: np.ndarray, *,
                   c_gnd: float = Param(lo=0.0, unit="N·s/m"), c_min: float = SOFT,
                   c_max: float = HARD) -> LawOutput:
    """Continuous groundhook c_gnd v_w clipped to c_min..c_max (thesis Eq 2.4)."""
    return recording_c(*groundhook_continuous(v_w, v_rel, c_gnd, c_min, c_max))
