"""Damage of a duty cycle (a proving-ground schedule of events) and life at a probability.

An event is one pass of a road (a run): its Miner damage per node ``D_e`` for one pass of
length ``L_e`` [m], driven ``n_e`` times in the schedule. Miner's rule is linear, so

    D[node] = sum_e n_e D_e[node]          (damage of one schedule)
    life    = 1 / max_node D               (schedules), x sum_e n_e L_e / 1000 (km)

and the event that dominates the critical node c is the one with the largest n_e D_e[c].

Certainty of survival. The S-N curve the damage is computed with is the median one (50 %
survival: every Marin factor is a mean regression; ``fatigue.component.reliability = 0.5``).
With a log-normal scatter of the life at a given stress, ``log10 N ~ Normal(log10 N50, s)``,
the same at every stress level, the curve at survival probability P is N_P = N50 10^(-z_P s)
(z_P the standard normal quantile of P), so every damage is multiplied and the life divided
by 10^(z_P s):

    life_P = life_50 x 10^(-z_P s).

The scatter is given as ``s`` (standard deviation of log10 N) or as the scatter band
T_N = N_10 / N_90 (lives at 10 % and 90 % survival; Haibach's 1 : T_N), s = log10 T_N / (2 z_0.9).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.stats import norm

Z_90 = float(norm.ppf(0.9))
"""Standard normal quantile of 90 % (1.2816): T_N spans z = -Z_90 ... +Z_90."""


@dataclass(frozen=True)
class Event:
    """One event of a schedule: damage per pass per node, pass length [m], repeats."""

    name: str
    damage: np.ndarray
    length_m: float
    repeats: float


@dataclass(frozen=True)
class DutyResult:
    """Damage of one schedule: ``per_event[e, node] = n_e D_e[node]``; ``total`` their sum."""

    names: list[str]
    per_event: np.ndarray
    total: np.ndarray
    distance_m: float

    @property
    def critical(self) -> int:
        """Index of the node with the largest schedule damage."""
        return int(np.argmax(self.total))

    @property
    def max_damage(self) -> float:
        return float(self.total[self.critical])

    @property
    def life_schedules(self) -> float:
        """Life in repeats of the whole schedule (1 / max D)."""
        return math.inf if self.max_damage == 0 else 1.0 / self.max_damage

    @property
    def life_km(self) -> float:
        return self.life_schedules * self.distance_m / 1000.0

    @property
    def dominant(self) -> int:
        """Index of the event with the largest share of the critical node's damage."""
        return int(np.argmax(self.per_event[:, self.critical]))

    def shares(self, node: int | None = None) -> np.ndarray:
        """Each event's fraction of the damage at ``node`` (default: the critical node)."""
        col = self.per_event[:, self.critical if node is None else node]
        s = float(col.sum())
        return col / s if s > 0 else np.zeros_like(col)


def schedule_damage(events: Sequence[Event]) -> DutyResult:
    """Sum the events' damages times their repeats, node by node (Miner's rule)."""
    if not events:
        raise ValueError("a duty cycle needs at least one event")
    n = events[0].damage.shape
    for e in events:
        if e.damage.shape != n:
            raise ValueError(f"event {e.name!r} has damage on {e.damage.size} nodes, "
                             f"{events[0].name!r} on {events[0].damage.size}")
        if not (e.repeats >= 0 and math.isfinite(e.repeats)):
            raise ValueError(f"event {e.name!r}: repeats must be >= 0, got {e.repeats!r}")
        if not (e.length_m > 0 and math.isfinite(e.length_m)):
            raise ValueError(f"event {e.name!r}: pass length must be > 0, got {e.length_m!r}")
    per = np.stack([np.asarray(e.damage, dtype=float) * e.repeats for e in events])
    return DutyResult(names=[e.name for e in events], per_event=per, total=per.sum(axis=0),
                      distance_m=float(sum(e.repeats * e.length_m for e in events)))


def log10_std_from_scatter_band(t_n: float) -> float:
    """s = log10(T_N) / (2 z_0.9), T_N = N_10 / N_90 >= 1."""
    if not (t_n >= 1.0 and math.isfinite(t_n)):
        raise ValueError(f"scatter band T_N = N10/N90 must be >= 1, got {t_n!r}")
    return math.log10(t_n) / (2.0 * Z_90)


def life_factor(probability: float, log10_std: float) -> float:
    """life_P / life_50 = 10^(-z_P s) for survival probability P in (0, 1)."""
    if not 0.0 < probability < 1.0:
        raise ValueError(f"survival probability must be in (0, 1), got {probability!r}")
    if not (log10_std >= 0 and math.isfinite(log10_std)):
        raise ValueError(f"std of log10 N must be >= 0, got {log10_std!r}")
    return 10.0 ** (-float(norm.ppf(probability)) * log10_std)


def law_matrix(results: Sequence[DutyResult]) -> tuple[int, np.ndarray]:
    """The schedule under several damper laws (``results``, the first the reference, the
    same events and nodes): (the reference's critical node c, D[law, event] = n_e D_e[c]
    under each law). One node for every law, so that a law's effect on an event is a ratio
    of damages at the same place (each law's own critical node and life are its result's)."""
    if not results:
        raise ValueError("no laws to compare")
    ref = results[0]
    for r in results[1:]:
        if r.names != ref.names or r.per_event.shape != ref.per_event.shape:
            raise ValueError("the laws' schedules have other events or nodes than the first's")
    c = ref.critical
    return c, np.stack([r.per_event[:, c] for r in results])
