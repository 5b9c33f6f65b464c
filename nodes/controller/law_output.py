"""What a semi-active law returns to the registry: ``(F_d, c_eff, extras)``, with the
channel that says how the damper was set.

A two-state law records ``state`` (1 hard, 0 soft), a variable-damper law records ``c``
(its coefficient, N·s/m); the laws of :mod:`nodes.controller.skyhook` and
:mod:`nodes.controller.groundhook` return their pure function's result through these two.
"""

from __future__ import annotations

import numpy as np

LawOutput = tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]
"""(F_d in N, c_eff in N·s/m, extra channels): see :mod:`nodes.controller.registry`."""


def recording_state(F_d: np.ndarray, c: np.ndarray, hard: np.ndarray) -> LawOutput:
    """A two-state law's output: force (N), coefficient (N·s/m) and ``state`` = the hard
    flag as 1.0/0.0."""
    return F_d, c, {"state": np.asarray(hard).astype(float)}


def recording_c(F_d: np.ndarray, c: np.ndarray) -> LawOutput:
    """A variable-damper law's output: force (N), coefficient (N·s/m), recorded as ``c``."""
    return F_d, c, {"c": c}
