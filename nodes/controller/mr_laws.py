"""Control laws that drive the MR damper of Table 5.1 through its current.

* ``passive_mr`` — constant current (the thesis's "passive MR" benchmark at 0 A, Fig 5.7a).
* TSS3 — Karnopp switching of the current: ``I_hard`` (0.6 A) where ``v_b * v_rel < 0``,
  ``I_soft`` (0 A) elsewhere (thesis Sec 5.3.3).
* TSS2 — the MR force tracks the TSS1 force ``F* = c_{soft|hard} * v_rel`` by feedback on the
  current (thesis Sec 5.3.2, Fig 5.6, after Sims et al. [118]; the block diagram is withheld
  in the thesis). Chosen form, with the published gains B = 0.8, G = 0.001 A/N::

      I = sat_[0, I_max]( G * (|F*| - B * |F_MR|) )

  ``F_MR`` is the damper's (fluid-spring) force. For a Bingham damper ``F = c v + a I`` and
  ``F* = K v`` the loop gives ``F = (c + a G K) v / (1 + a G B)``: viscous-like ("feedback
  linearisation"), B < 1 making up the droop. It is evaluated every internal substep (the
  thesis's Simulink block ran at its own fine rate); without fluid dynamics, solved exactly.

The MR model is integrated from the previous call to ``t``, the velocities interpolated
linearly, so the force returned is the damper's at ``t``; ``c_eff`` = ``r^2 c_post(I)``.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from nodes.controller.base import Controller, ControlOutput
from nodes.controller.mr_damper import MRDamper, MRParams
from nodes.controller.skyhook import skyhook_condition


def tss2_current(F_star: np.ndarray, F_mr: np.ndarray, B: float, G: float,
                 I_max: float) -> np.ndarray:
    """TSS2 current ``sat_[0, I_max](G (|F*| - B |F_MR|))`` (A): F* the TSS1 demand and F_MR
    the damper's force (N), B (-) and G (A/N) the gains (thesis 0.8, 0.001), I_max (A)."""
    return np.clip(G * (np.abs(F_star) - B * np.abs(F_mr)), 0.0, I_max)


class MRController(Controller):
    """Base of the MR laws: owns an :class:`MRDamper` per corner and the interpolation of the
    inputs between calls. Subclasses give the current rule."""

    fixed_step = True  # the damper's first-order current lag, integrated with h

    def __init__(self, n_corners: int, h: float, params: MRParams) -> None:
        super().__init__(n_corners, h)
        self.damper = MRDamper(n_corners, params)
        self._t: float | None = None
        self._v_b = np.zeros(n_corners)
        self._v_rel = np.zeros(n_corners)

    def current(self, v_b: np.ndarray, v_rel: np.ndarray, F_mr: np.ndarray) -> np.ndarray:
        """Current (A) for body velocity, relative velocity and present damper force."""
        raise NotImplementedError

    def demand(self, v_b: np.ndarray, v_rel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(force demand in N, hard flag) recorded with the output."""
        hard = skyhook_condition(v_b, v_rel)
        return np.full(self.n, np.nan), hard

    def _first_current(self, v_b: np.ndarray, v_rel: np.ndarray) -> np.ndarray:
        return self.current(v_b, v_rel, np.zeros(self.n))

    def step(self, t: float, state: Mapping[str, np.ndarray]) -> ControlOutput:
        v_b, _, v_rel = self.corners(state)
        d = self.damper
        if self._t is None:
            F = d.start(v_rel, self._first_current(v_b, v_rel))
        else:
            v_b0, v_rel0 = self._v_b, self._v_rel

            def rule(frac: float, F_now: np.ndarray) -> np.ndarray:
                vb = v_b0 + frac * (v_b - v_b0)
                vr = v_rel0 + frac * (v_rel - v_rel0)
                return self.current(vb, vr, F_now)

            F = d.advance(v_rel0, v_rel, float(t) - self._t, rule)
        self._t, self._v_b, self._v_rel = float(t), v_b.copy(), v_rel.copy()
        F_dem, hard = self.demand(v_b, v_rel)
        I = d.I.copy()
        return ControlOutput(F_d=F.copy(), c_eff=d.c_eff(I),
                             extra={"I": I, "state": hard.astype(float), "F_demand": F_dem})


class PassiveMR(MRController):
    """MR damper at a constant current ``I`` (A); 0 A is the thesis's "passive MR"."""

    law = "passive_mr"

    def __init__(self, n_corners: int, h: float, params: MRParams, I: float) -> None:
        super().__init__(n_corners, h, params)
        self.I = I

    def current(self, v_b: np.ndarray, v_rel: np.ndarray, F_mr: np.ndarray) -> np.ndarray:
        return np.full(self.n, self.I)

    def demand(self, v_b: np.ndarray, v_rel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return np.full(self.n, np.nan), np.zeros(self.n, dtype=bool)


class TSS3(MRController):
    """Two-state skyhook switching the MR current: ``I_hard`` where ``v_b * v_rel < 0``, else
    ``I_soft`` (thesis: 0.6 A / 0 A)."""

    law = "tss3"

    def __init__(self, n_corners: int, h: float, params: MRParams, I_soft: float,
                 I_hard: float) -> None:
        super().__init__(n_corners, h, params)
        self.I_soft, self.I_hard = I_soft, I_hard

    def current(self, v_b: np.ndarray, v_rel: np.ndarray, F_mr: np.ndarray) -> np.ndarray:
        return np.where(skyhook_condition(v_b, v_rel), self.I_hard, self.I_soft)


class TSS2(MRController):
    """MR force tracking the TSS1 force (c_soft, c_hard in N·s/m) by current feedback with the
    gains B (-) and G (A/N) (module docstring)."""

    law = "tss2"

    def __init__(self, n_corners: int, h: float, params: MRParams, c_soft: float,
                 c_hard: float, B: float, G: float) -> None:
        super().__init__(n_corners, h, params)
        self.c_soft, self.c_hard, self.B, self.G = c_soft, c_hard, B, G

    def f_star(self, v_b: np.ndarray, v_rel: np.ndarray) -> np.ndarray:
        """TSS1 force the damper should give (N)."""
        return np.where(skyhook_condition(v_b, v_rel), self.c_hard, self.c_soft) * v_rel

    def current(self, v_b: np.ndarray, v_rel: np.ndarray, F_mr: np.ndarray) -> np.ndarray:
        F_star = self.f_star(v_b, v_rel)
        if not self.damper.p.dynamics:
            return self._solve_static(F_star, v_rel)
        return tss2_current(F_star, F_mr, self.B, self.G, self.damper.p.I_max)

    def _first_current(self, v_b: np.ndarray, v_rel: np.ndarray) -> np.ndarray:
        return self._solve_static(self.f_star(v_b, v_rel), v_rel)

    def _solve_static(self, F_star: np.ndarray, v_rel: np.ndarray) -> np.ndarray:
        """Solve ``I = sat(G (|F*| - B |F_MR(v_rel, I)|))`` for the static damper (bisection;
        the right side falls with I because the MR force rises with I on [0, 0.6] A)."""
        I_max = self.damper.p.I_max

        def gap(I: np.ndarray) -> np.ndarray:
            F = self.damper.static_force(v_rel, I)
            return I - self.G * (np.abs(F_star) - self.B * np.abs(F))

        lo = np.zeros(self.n)
        hi = np.full(self.n, I_max)
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            up = gap(mid) > 0.0
            hi = np.where(up, mid, hi)
            lo = np.where(up, lo, mid)
        I = 0.5 * (lo + hi)
        I = np.where(gap(np.zeros(self.n)) >= 0.0, 0.0, I)
        return np.where(gap(np.full(self.n, I_max)) <= 0.0, I_max, I)

    def demand(self, v_b: np.ndarray, v_rel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.f_star(v_b, v_rel), skyhook_condition(v_b, v_rel)
