"""The fatigue result of one analysed history (one pass of the track): damage, extremes and
ranges per node, the lives they give (Eq 2.7: life = 1 / D passes = L / D metres) and its
JSON summary. Made by :mod:`.worker` (batch or live), written by :mod:`.outputs`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class FatigueResult:
    """Fatigue result of one analysed history (one pass of the track).

    Arrays are per analysed node. Stresses in Pa, lengths in m (life also in km).
    """

    damage: np.ndarray  # Miner damage D per pass
    node_ids: np.ndarray
    node_xyz: np.ndarray | None
    eq_max: np.ndarray  # max equivalent stress (Pa)
    eq_min: np.ndarray  # min equivalent stress (Pa)
    eq_range_max: np.ndarray  # largest counted cycle range (Pa)
    n_cycles: np.ndarray  # counted cycles (full + 0.5 x half)
    track_length_m: float
    duration_s: float
    n_samples: int
    config: dict
    influence_meta: dict = field(default_factory=dict)
    missing_channels: list[str] = field(default_factory=list)
    repeats_basis_m: float | None = None
    source: str = "batch"  # "batch" (a finished run's table) or "live" (during the run)
    screened: np.ndarray | None = None
    """Per node: True where screening left the node out (its damage, extremes and range are
    then upper bounds, its cycle count NaN); None: every node computed."""
    screening: dict = field(default_factory=dict)

    @property
    def critical_node(self) -> int:
        """Index (into the arrays) of the node with the largest damage."""
        return int(np.argmax(self.damage))

    @property
    def critical_node_id(self) -> int:
        return int(self.node_ids[self.critical_node])

    @property
    def critical_xyz(self) -> list[float] | None:
        return None if self.node_xyz is None else self.node_xyz[self.critical_node].tolist()

    @property
    def max_damage(self) -> float:
        return float(self.damage.max()) if self.damage.size else 0.0

    @property
    def life_repeats(self) -> float:
        """Minimum life in repeats of the simulated track (1 / max D)."""
        d = self.max_damage
        return float("inf") if d == 0.0 else 1.0 / d

    @property
    def life_km(self) -> float:
        return self.life_repeats * self.track_length_m / 1000.0

    @property
    def life_repeats_basis(self) -> float | None:
        """Minimum life in repeats of ``repeats_basis_m`` (e.g. the thesis's 100 m pavé)."""
        if self.repeats_basis_m is None:
            return None
        return self.life_km * 1000.0 / self.repeats_basis_m

    def life_repeats_per_node(self) -> np.ndarray:
        with np.errstate(divide="ignore"):
            return np.where(self.damage > 0, 1.0 / self.damage, np.inf)

    def summary(self) -> dict:
        """JSON-able summary (infinite lives become the string "inf")."""

        def f(x):
            return x if x is None or np.isfinite(x) else "inf"

        top = np.argsort(self.damage)[::-1][:10]
        return {
            "min_life_repeats": f(self.life_repeats),
            "min_life_km": f(self.life_km),
            "min_life_repeats_basis": f(self.life_repeats_basis),
            "repeats_basis_m": self.repeats_basis_m,
            "max_damage_per_pass": self.max_damage,
            "critical_node_id": self.critical_node_id,
            "critical_node_xyz_m": self.critical_xyz,
            "critical_eq_range_max_pa": float(self.eq_range_max[self.critical_node]),
            "track_length_m": self.track_length_m,
            "duration_s": self.duration_s,
            "n_samples": self.n_samples,
            "n_nodes": int(self.damage.size),
            "eq_stress_max_pa": float(self.eq_max.max()),
            "eq_stress_min_pa": float(self.eq_min.min()),
            "top_nodes": [{"node_id": int(self.node_ids[i]), "damage": float(self.damage[i]),
                           "life_km": f(self.track_length_m / 1000.0 / self.damage[i]
                                        if self.damage[i] > 0 else float("inf"))}
                          for i in top],
            "missing_channels": list(self.missing_channels),
            "config": self.config,
            "influence": self.influence_meta,
            "source": self.source,
            **({"screening": self.screening} if self.screening else {}),
        }
