"""Palmgren-Miner damage per node by ``np.bincount`` over a batch of counted cycles: the
oracle the worker's block engine (its cycles' damages summed per node as they close,
``np.add.at``: :mod:`nodes.fatigue.worker`) is checked against."""

from __future__ import annotations

import numpy as np

from nodes.fatigue.lib.counting import Cycles
from nodes.fatigue.lib.damage import cycle_damage
from nodes.fatigue.lib.material import Material


def miner_per_node(cycles: Cycles, n_nodes: int, mat: Material, method: str,
                   mean_stress: str, endurance_limit: str | None = None) -> np.ndarray:
    """Palmgren-Miner damage D per node (sum of cycle damages)."""
    d = cycle_damage(cycles, mat, method, mean_stress, endurance_limit)
    return np.bincount(cycles.series, weights=d, minlength=n_nodes).astype(float)
