"""Hybrid skyhook-groundhook law (thesis Eq 2.5, Ahmadian [78]).

Thesis: ``F_sa = G [alpha sigma_sh + (1 - alpha) sigma_gh]`` with ``sigma_sh = z_b'`` where
``z_b'(z_b' - z_w') > 0`` (else 0) and ``sigma_gh = z_w'`` where ``-z_w'(z_b' - z_w') > 0``
(else 0). alpha = 1 is skyhook, alpha = 0 groundhook.

Here, as a force on the body: the skyhook part is ``-v_b`` and the groundhook part ``+v_w``
(each only where dissipative), so

    F_demand = G [alpha (-v_b) [v_b v_rel < 0] + (1 - alpha) v_w [v_w v_rel > 0]]

and both parts have the sign of ``v_rel``: the demand is always dissipative. It is realised by
a variable damper with ``c_min <= c <= c_max``.
"""

from __future__ import annotations

import numpy as np

from nodes.controller.dampers import semi_active_force
from nodes.controller.groundhook import groundhook_condition
from nodes.controller.registry import HARD, SOFT, Param, control_law
from nodes.controller.skyhook import skyhook_condition


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
               c_max: float = HARD):
    """Hybrid skyhook-groundhook G [alpha sky + (1 - alpha) ground] (thesis Eq 2.5)."""
    F, c = hybrid(v_b, v_w, alpha, G, c_min, c_max)
    return F, c, {"c": c}
