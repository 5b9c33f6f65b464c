"""The joint centres a part file may name as ``"hardpoint:NAME"`` (docs/parts.md): the plant's
hardpoints, read from their one definition (the built-in corner file
``cosim/corners/mpv_front.toml`` through :mod:`cosim.lower_arm` and :mod:`cosim.corner`),
each in the frame of the part it belongs to [m]:

* the lower arm's, in its arm frame (:data:`cosim.lower_arm.HARDPOINTS`): ``bush_front``,
  ``bush_rear``, ``ball_joint``, ``damper_mount``, ``bump_stop``;
* the upper arm's, in the upper-arm frame (the frame of ``plant/upper_arm``: the lower arm's
  rule, :func:`cosim.lower_arm.arm_frame_of`, applied to the corner's upper points; origin the
  upper bushes' midpoint, x rear -> front bush, y toward the upper ball joint, z = x cross
  y): ``upper_bush_front``, ``upper_bush_rear``, ``upper_ball_joint`` (the corner file's
  names, and the ``plant/upper_arm`` fields' stems).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

UPPER_POINTS = {"bush_front": "upper_bush_front", "bush_rear": "upper_bush_rear",
                "ball_joint": "upper_ball_joint"}
"""The lower-arm point names of :func:`cosim.lower_arm.hardpoints_of` -> the corner file's
upper-arm points (as nodes/plant/upper_arm_loads.py; tests/fatigue/test_part_upper_arm.py
checks that both give the same points)."""


def hardpoints() -> dict[str, np.ndarray]:
    """Every named hardpoint, each in its part's frame [m]."""
    from cosim import corner, lower_arm

    out = {k: np.asarray(v, dtype=float) for k, v in lower_arm.HARDPOINTS.items()}
    c = corner.builtin()
    upper = replace(c, points={f"lower_{k}": c.points[v] for k, v in UPPER_POINTS.items()})
    for k, v in lower_arm.hardpoints_of(upper).items():
        out[UPPER_POINTS[k]] = v
    return out
