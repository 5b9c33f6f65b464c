"""Skyhook laws: two-state (TSS1, thesis Eq 5.3), continuous (clipped), and no-jerk.

Convention: ``v_rel = v_w - v_b`` (m/s, compression positive), ``F_d`` on the body upward
positive (N). The ideal skyhook force on the body is ``-c_sky * v_b`` (Karnopp, thesis Eq 2.2);
a semi-active damper can give it only when it has the sign of ``v_rel``, i.e. when

    v_b * v_rel < 0   <=>   z_b' * (z_b' - z_w') > 0   (the thesis's switching condition).
"""

from __future__ import annotations

import numpy as np

from nodes.controller.dampers import semi_active_force, two_state_force
from nodes.controller.law_output import LawOutput, recording_c, recording_state
from nodes.controller.registry import HARD, SOFT, Param, control_law


def skyhook_condition(v_b: np.ndarray, v_rel: np.ndarray) -> np.ndarray:
    """True where the skyhook force is dissipative: ``v_b * v_rel < 0`` (strict; a tie is
    "off", i.e. soft, as the thesis leaves it unspecified)."""
    return np.asarray(v_b, dtype=float) * np.asarray(v_rel, dtype=float) < 0.0


def skyhook_on_off(v_b: np.ndarray, v_rel: np.ndarray, c_soft: float, c_hard: float
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Two-state skyhook TSS1 (thesis Eq 5.3, Moline [44]): (F_d in N, c in N·s/m, hard flag).

    Thesis: ``c = C_hard if z_b'(z_b' - z_w') > 0 else C_soft``, ``F_d = c (z_b' - z_w')``;
    here ``c = c_hard if v_b * v_rel < 0 else c_soft``, ``F_d = c * v_rel`` (v in m/s).
    Table 5.2: 1500/2368 N·s/m (lumped QVM, 7-DOF FVM), 3800/6000 (realistic QVM)."""
    hard = skyhook_condition(v_b, v_rel)
    return (*two_state_force(hard, v_rel, c_soft, c_hard), hard)


def skyhook_continuous(v_b: np.ndarray, v_rel: np.ndarray, c_sky: float, c_min: float,
                       c_max: float) -> tuple[np.ndarray, np.ndarray]:
    """Continuous skyhook, demand ``-c_sky * v_b`` (Karnopp, thesis Eq 2.2) realised by
    :func:`semi_active_force`: (F_d in N, c in N·s/m)."""
    F_dem = -c_sky * np.asarray(v_b, dtype=float)
    return semi_active_force(F_dem, v_rel, c_min, c_max)


def skyhook_no_jerk_demand(v_b: np.ndarray, v_rel: np.ndarray, G: float) -> np.ndarray:
    """No-jerk skyhook demand (Ahmadian [49,50]), N: ``c_sky = G |v_rel|`` (G in N·s²/m²),
    so the demand ``G |v_b| v_rel`` goes to zero at both ends of the "on" region (no jump at
    switching); zero where the skyhook force is not dissipative."""
    v_b = np.asarray(v_b, dtype=float)
    v_rel = np.asarray(v_rel, dtype=float)
    return np.where(skyhook_condition(v_b, v_rel), G * np.abs(v_b) * v_rel, 0.0)


def skyhook_no_jerk(
    v_b: np.ndarray, v_rel: np.ndarray, G: float, c_min: float, c_max: float
) -> tuple[np.ndarray, np.ndarray]:
    """No-jerk skyhook by a variable damper, ``c = clip(G |v_b|, c_min, c_max)`` in the
    skyhook region, ``c_min`` elsewhere: (F_d in N, c in N·s/m)."""
    return semi_active_force(skyhook_no_jerk_demand(v_b, v_rel, G), v_rel, c_min, c_max)


# ------------------------------------------------------------------ the laws, by name


@control_law("tss1", aliases=("skyhook_on_off",))
def tss1_law(v_b: np.ndarray, v_rel: np.ndarray, *, c_soft: float = SOFT,
             c_hard: float = HARD) -> LawOutput:
    """Two-state skyhook TSS1 (thesis Eq 5.3): c_hard where v_b v_rel < 0, else c_soft."""
    return recording_state(*skyhook_on_off(v_b, v_rel, c_soft, c_hard))


@control_law("skyhook")
def skyhook_law(v_b: np.ndarray, v_rel: np.ndarray, *, c_sky: float = Param(lo=0.0, unit="N·s/m"),
                c_min: float = SOFT, c_max: float = HARD) -> LawOutput:
    """Continuous skyhook -c_sky v_b clipped to c_min..c_max (thesis Eq 2.2)."""
    return recording_c(*skyhook_continuous(v_b, v_rel, c_sky, c_min, c_max))


@control_law("skyhook_no_jerk")
def skyhook_no_jerk_law(v_b: np.ndarray, v_rel: np.ndarray, *,
                        G: float = Param(lo=0.0, unit="N·s²/m²"), c_min: float = SOFT,
                        c_max: float = HARD) -> LawOutput:
    """No-jerk skyhook c = clip(G |v_b|) in the skyhook region (Ahmadian [49,50])."""
    return recording_c(*skyhook_no_jerk(v_b, v_rel, G, c_min, c_max))
