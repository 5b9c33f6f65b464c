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


def _state(F_d: np.ndarray, c: np.ndarray, hard: np.ndarray) -> LawOutput:
    return F_d, c, {"state": np.asarray(hard).astype(float)}


def _c(F_d: np.ndarray, c: np.ndarray) -> LawOutput:
    return F_d, c, {"c": c}


def skyhook_condition(v_b: np.ndarray, v_rel: np.ndarray) -> np.ndarray:
    """True where the skyhook force is dissipative: ``v_b * v_rel < 0`` (strict; a tie is
    "off", i.e. soft, as the thesis leaves it unspecified)."""
    return np.asarray(v_b, dtype=float) * np.asarray(v_rel, dtype=float) < 0.0


def groundhook_condition(v_w: np.ndarray, v_rel: np.ndarray) -> np.ndarray:
    """True where the groundhook force is dissipative: ``v_w * v_rel > 0``."""
    return np.asarray(v_w, dtype=float) * np.asarray(v_rel, dtype=float) > 0.0


@control_law("tss1", aliases=("skyhook_on_off",))
def skyhook_on_off(v_b: np.ndarray, v_rel: np.ndarray, *, c_soft: float = SOFT,
                   c_hard: float = HARD) -> LawOutput:
    """Two-state skyhook TSS1 (thesis Eq 5.3): c_hard where v_b v_rel < 0, else c_soft.

    Moline [44]; the thesis's ``c = C_hard if z_b'(z_b' - z_w') > 0 else C_soft``. Table 5.2:
    1500/2368 N·s/m (lumped QVM, 7-DOF FVM), 3800/6000 (realistic QVM)."""
    hard = skyhook_condition(v_b, v_rel)
    return _state(*two_state_force(hard, v_rel, c_soft, c_hard), hard)


@control_law("skyhook")
def skyhook_continuous(v_b: np.ndarray, v_rel: np.ndarray, *,
                       c_sky: float = Param(lo=0.0, unit="N·s/m"), c_min: float = SOFT,
                       c_max: float = HARD) -> LawOutput:
    """Continuous skyhook -c_sky v_b clipped to c_min..c_max (thesis Eq 2.2).

    The demand ``-c_sky * v_b`` (Karnopp) realised by :func:`semi_active_force`."""
    return _c(*semi_active_force(-c_sky * np.asarray(v_b, dtype=float), v_rel, c_min, c_max))


@control_law("skyhook_no_jerk")
def skyhook_no_jerk(v_b: np.ndarray, v_rel: np.ndarray, *,
                    G: float = Param(lo=0.0, unit="N·s²/m²"), c_min: float = SOFT,
                    c_max: float = HARD) -> LawOutput:
    """No-jerk skyhook c = clip(G |v_b|) in the skyhook region (Ahmadian [49,50]).

    ``c_sky = G |v_rel|``, so the demand ``G |v_b| v_rel`` goes to zero at both ends of the
    "on" region (no jump at switching); ``c_min`` where the skyhook force is not dissipative."""
    v_b, v_rel = np.asarray(v_b, dtype=float), np.asarray(v_rel, dtype=float)
    F_dem = np.where(skyhook_condition(v_b, v_rel), G * np.abs(v_b) * v_rel, 0.0)
    return _c(*semi_active_force(F_dem, v_rel, c_min, c_max))


@control_law("groundhook_on_off")
def groundhook_on_off(v_w: np.ndarray, v_rel: np.ndarray, *, c_soft: float = SOFT,
                      c_hard: float = HARD) -> LawOutput:
    """Two-state groundhook: c_hard where v_w v_rel > 0, else c_soft (thesis Eq 2.4)."""
    hard = groundhook_condition(v_w, v_rel)
    return _state(*two_state_force(hard, v_rel, c_soft, c_hard), hard)


@control_law("groundhook")
def groundhook_continuous(v_w: np.ndarray, v_rel: np.ndarray, *,
                          c_gnd: float = Param(lo=0.0, unit="N·s/m"), c_min: float = SOFT,
                          c_max: float = HARD) -> LawOutput:
    """Continuous groundhook c_gnd v_w clipped to c_min..c_max (thesis Eq 2.4)."""
    return _c(*semi_active_force(c_gnd * np.asarray(v_w, dtype=float), v_rel, c_min, c_max))


@control_law("hybrid")
def hybrid(v_b: np.ndarray, v_w: np.ndarray, *, alpha: float = Param(lo=0.0, hi=1.0),
           G: float = Param(lo=0.0, unit="N·s/m"), c_min: float = SOFT,
           c_max: float = HARD) -> LawOutput:
    """Hybrid skyhook-groundhook G [alpha sky + (1 - alpha) ground] (thesis Eq 2.5)."""
    v_b, v_w = np.asarray(v_b, dtype=float), np.asarray(v_w, dtype=float)
    v_rel = v_w - v_b
    sigma_sh = np.where(skyhook_condition(v_b, v_rel), -v_b, 0.0)
    sigma_gh = np.where(groundhook_condition(v_w, v_rel), v_w, 0.0)
    F_dem = G * (alpha * sigma_sh + (1.0 - alpha) * sigma_gh)
    return _c(*semi_active_force(F_dem, v_rel, c_min, c_max))
