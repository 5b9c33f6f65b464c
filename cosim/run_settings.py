"""The run's settings, typed and read once: :class:`RunSettings` from the resolved scenario's
``[run]`` table, and the lag rule of the exchange in one place (:meth:`RunSettings.needs`).

``run.exchange`` ``sequential`` (the thesis's): the force nodes answer the plant's state at
t_k with the forces at t_k, then the plant integrates to t_{k+1}; ``parallel`` (Jacobi): every
node steps on the previous step's inputs, so the inputs of :data:`LAGGED` (the plant's state,
for the force nodes) are of step k - 1 (step 0: of step 0).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from .errors import ScenarioError
from .step_size import AdaptiveStep

LAGGED: frozenset[tuple[str, str]] = frozenset({("plant", "state")})
"""Inputs a node takes from the previous step in the parallel exchange."""
EXCHANGES = ("sequential", "parallel")


@dataclass(frozen=True)
class RunSettings:
    """The settings of one run every node shell needs (``[run]`` of the resolved scenario)."""

    h: float  # communication step [s]
    n_steps: int | None  # N: steps k = 0..N (None before the scenario is resolved)
    exchange: str
    coupling: str
    substeps: int
    stall_timeout_s: float
    start_timeout_s: float
    t_end: float = 0.0  # simulated time [s] (t_N)
    adaptive: AdaptiveStep | None = None
    """``run.h = "auto"``: the step is chosen as the run goes (:mod:`cosim.step_size`); then
    :attr:`h` is h_min and :attr:`n_steps` an upper bound, and a node knows the last step by
    its time (:meth:`is_last`)."""

    @classmethod
    def of(cls, scenario: Mapping[str, Any]) -> RunSettings:
        """The settings of a resolved ``scenario`` (ScenarioError naming a bad key)."""
        run = scenario.get("run")
        if not isinstance(run, Mapping):
            raise ScenarioError("run", run, "a [run] table")
        try:
            n = run.get("n_steps")
            settings = cls(h=float(run["h"]), n_steps=None if n is None else int(n),
                           exchange=str(run.get("exchange", "sequential")),
                           coupling=str(run.get("coupling", "jacobian")),
                           substeps=int(run.get("substeps", 1)),
                           stall_timeout_s=float(run.get("stall_timeout_s", 5.0)),
                           start_timeout_s=float(run.get("start_timeout_s", 60.0)),
                           t_end=float(run.get("t_end", 0.0)),
                           adaptive=AdaptiveStep.of_run(dict(run)))
        except KeyError as exc:
            raise ScenarioError(f"run.{exc.args[0]}", None, "a value") from None
        except (TypeError, ValueError) as exc:
            raise ScenarioError("run", dict(run), f"numbers where numbers go ({exc})") from None
        if settings.exchange not in EXCHANGES:
            raise ScenarioError("run.exchange", settings.exchange, " or ".join(EXCHANGES))
        return settings

    def is_last(self, k: int, t: float) -> bool:
        """Whether step ``k`` at ``t`` [s] is the last: k = N, or t = t_end (adaptive)."""
        if self.adaptive is not None:
            return self.adaptive.is_last(t, self.t_end)
        return k == self.n_steps

    @property
    def lag(self) -> int:
        """Steps a lagged input is behind: 0 sequential, 1 parallel."""
        return 0 if self.exchange == "sequential" else 1

    def needs(self, tags: list[tuple[str, str]], k: int) -> dict[tuple[str, str], int]:
        """``{input: step}`` that step ``k`` is computed from (for ``Participant.wait``)."""
        lag = self.lag
        if not lag:
            return {tag: k for tag in tags}
        return {tag: max(k - lag, 0) if tag in LAGGED else k for tag in tags}
