"""Acceleration-driven damper, ADD (Savaresi, Silani & Bittanti 2005, "Acceleration-Driven-Damper
(ADD): an optimal control algorithm for comfort-oriented semiactive suspensions", ASME J. Dyn.
Sys. Meas. Control 127(2)): the comfort-optimal two-state law that switches on the body's
acceleration instead of its velocity.

Paper: ``c = c_max if z_b'' (z_b' - z_w') > 0 else c_min`` (extension-positive velocity).
Here (``v_rel = v_w - v_b``, compression positive): ``c = c_hard where a_b * v_rel < 0`` --
hard when the damper force ``c v_rel`` on the body opposes its acceleration -- and
``F_d = c v_rel``. The controller sees the plant's state only, so ``a_b`` (m/s²) is the
backward difference of ``v_b`` between two calls (0 at the first call: soft).
"""

from __future__ import annotations

import numpy as np

from nodes.controller.dampers import two_state_force
from nodes.controller.registry import HARD, SOFT, control_law


@control_law("add")
def add_law(t: float, v_b: np.ndarray, v_rel: np.ndarray, memory: dict, *,
            c_soft: float = SOFT, c_hard: float = HARD):
    """Acceleration-driven damper (Savaresi 2005): c_hard where a_b v_rel < 0, else c_soft."""
    t_prev, v_prev = memory.get("prev", (t, v_b))
    a_b = (v_b - v_prev) / (t - t_prev) if t > t_prev else np.zeros_like(v_b)
    memory["prev"] = (t, v_b.copy())
    hard = a_b * v_rel < 0.0
    F, c = two_state_force(hard, v_rel, c_soft, c_hard)
    return F, c, {"state": hard.astype(float), "a_b_est": a_b}
