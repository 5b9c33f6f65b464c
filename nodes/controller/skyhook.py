"""The Karnopp family: skyhook (two-state TSS1, thesis Eq 5.3; continuous, Eq 2.2; no-jerk),
groundhook (Eq 2.4) and hybrid (Eq 2.5) laws.

Convention: ``v_rel = v_w - v_b`` (m/s, compression positive), ``F_d`` on the body upward
positive (N). The ideal skyhook force on the body is ``-c_sky * v_b`` (Karnopp, thesis Eq 2.2);
a semi-active damper can give it only when it has the sign of ``v_rel``, i.e. when

    v_b * v_rel < 0   <=>   z_b' * (z_b' - z_w') > 0   (the thesis's switching condition).

The ideal groundhook force on the *wheel* is ``-c_gnd * v_w`` (Ahmadian [78]); the wheel gets
``-F_d``, so the demanded ``F_d = c_gnd * v_w``, dissipative when ``v_w * v_rel > 0``.

Hybrid (thesis Eq 2.5): ``F_sa = G [alpha sigma_sh + (1 - alpha) sigma_gh]`` with ``sigma_sh =
z_b'`` where ``z_b'(z_b' - z_w') > 0`` (else 0) and ``sigma_gh = z_w'`` where
``-z_w'(z_b' - z_w') > 0`` (else 0); alpha = 1 is skyhook, alpha = 0 groundhook. Here, as a
force on the body, the skyhook part is ``-v_b`` and the groundhook part ``+v_w`` (each only
where dissipative), so

    F_demand = G [alpha (-v_b) [v_b v_rel < 0] + (1 - alpha) v_w [v_w v_rel > 0]]

and both parts have the sign of ``v_rel``: the demand is always dissipative. It is realised by
a variable damper with ``c_min <= c <= c_max``.
"""

from __future__ import annotations

import numpy as np

from nodes.controller.dampers import semi_active_force, two_state_force
from nodes.controller.registry import HARD, SOFT, Param, control_law

LawOutput = tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]
"""(F_d in N, c_eff in N·s/m, extras): a two-state law records ``state`` (1 hard, 0 soft), a
variable-damper law ``c`` (its coefficient, N·s/m)."""


def recording_state(F_d: np.ndarray, c: np.ndarray, hard: np.ndarray) -> LawOutput:
    return F_d, c, {"state": np.asarray(hard).astype(float)}


def recording_c(F_d: np.ndarray, c: np.ndarray) -> LawOutput:
    return F_d, c, {"c": c}


def skyhook_condition(v_b: np.ndarray, v_rel: np.ndarray) -> np.ndarray:
    """True where the skyhook force is dissipative: ``v_b * v_rel < 0`` (strict; a tie is
    "off", i.e. soft, as the thesis leaves it unspecified)."""
    return np.asarray(v_b, dtype=float) * np.asarray(v_rel, dtype=float) < 0.0


def skyhook_on_off(v_b: np.ndarray, v_rel: np.ndarray, c_soft: float, c_hard: float
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Two-state skyhook TSS1 (thesis Eq 5.3, Moline [44]; ``c = C_hard if z_b'(z_b' - z_w')
    > 0 else C_soft``): ``c = c_hard if v_b * v_rel < 0 else c_soft``, ``F_d = c * v_rel``;
    (F_d in N, c in N·s/m, hard flag). Table 5.2: 1500/2368 N·s/m (lumped QVM, 7-DOF FVM),
    3800/6000 (realistic QVM)."""
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


def hybrid_demand(v_b: np.ndarray, v_w: np.ndarray, alpha: float, G: float) -> np.ndarray:
    """Hybrid force demand on the body (N) from ``v_b``, ``v_w`` (m/s), the skyhook share
    ``alpha`` in [0, 1] and the gain ``G`` (N·s/m)."""
    v_b = np.asarray(v_b, dtype=float)
    v_w = np.asarray(v_w, dtype=float)
    v_rel = v_w - v_b
    sigma_sh = np.where(skyhook_condition(v_b, v_rel), -v_b, 0.0)
    sigma_gh = np.where(groundhook_condition(v_w, v_rel), v_w, 0.0)
    return G * (alpha * sigma_sh + (1.0 - alpha) * sigma_gh)


def hybrid(v_b: np.ndarray, v_w: np.ndarray, alpha: float, G: float, c_min: float,
           c_max: float) -> tuple[np.ndarray, np.ndarray]:
    """Hybrid law realised by a variable damper. Returns (F_d in N, c in N·s/m)."""
    v_rel = np.asarray(v_w, dtype=float) - np.asarray(v_b, dtype=float)
    return semi_active_force(hybrid_demand(v_b, v_w, alpha, G), v_rel, c_min, c_max)


@control_law("hybrid")
def hybrid_law(v_b: np.ndarray, v_w: np.ndarray, *, alpha: float = Param(lo=0.0, hi=1.0),
               G: float = Param(lo=0.0, unit="N·s/m"), c_min: float = SOFT,
               c_max: float = HARD) -> LawOutput:
    """Hybrid skyhook-groundhook G [alpha sky + (1 - alpha) ground] (thesis Eq 2.5)."""
    return recording_c(*hybrid(v_b, v_w, alpha, G, c_min, c_max))


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
