"""Stress influence coefficients c_i (Pa per unit load) of a part.

An `InfluenceSet` holds, for n load cases and m nodes, the six stress components per unit
load: ``coefficients[i, node, :] = (σx, σy, σz, τxy, τyz, τzx)`` in Pa/N (Pa/(N m) for a unit
moment), with the name of the load channel each case answers to (``ball_joint_z`` answers to
the column ``plant/arm/ball_joint_z``). Where sets come from: :mod:`nodes.fatigue.influence`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class InfluenceSet:
    """Unit-load stresses: coefficients (n_cases, n_nodes, 6) in Pa per N."""

    case_names: list[str]
    coefficients: np.ndarray
    node_xyz: np.ndarray | None  # (n_nodes, 3) m, None if the import has no coordinates
    node_ids: np.ndarray  # (n_nodes,) labels (FE node numbers)
    surface: np.ndarray  # (n_nodes,) bool, nodes on the surface
    meta: dict = field(default_factory=dict)

    @property
    def n_nodes(self) -> int:
        return int(self.coefficients.shape[1])

    def subset(self, mask: np.ndarray) -> InfluenceSet:
        """The same set restricted to the nodes in ``mask``."""
        return InfluenceSet(
            list(self.case_names), np.ascontiguousarray(self.coefficients[:, mask]),
            None if self.node_xyz is None else self.node_xyz[mask], self.node_ids[mask],
            self.surface[mask], dict(self.meta),
        )


def short_channel(name: str) -> str:
    """``plant/arm/ball_joint_z`` -> ``ball_joint_z``."""
    return name[len("plant/arm/"):] if name.startswith("plant/arm/") else name
