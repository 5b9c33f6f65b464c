"""MR damper of thesis Table 5.1 (Carrera MagneShock): bi-viscous law with fluid stiffness and mass.

Static law (thesis Eq 5.2, body lost in the OCR; the standard continuous bi-viscous form of
Stanway/Wereley is used)::

    F_bv(v, I) = c_pre * v                          if |v| <= v_y(I)
               = F_y(I) * sgn(v) + c_post(I) * v    if |v| >  v_y(I)
    v_y(I)     = F_y(I) / (c_pre - c_post(I))       (the two branches meet: continuous)

``F_y`` is the *intercept* of the post-yield line (Bingham), the meaning of the published
polynomials (post-yield fits); a knee force F_y (v_y = F_y/c_pre) would lower every
post-yield force by ``F_y c_post / c_pre`` (~100 N at 0.6 A). See docs/control.md.

Current dependence (Table 5.1, valid for 0 <= I <= 0.6 A)::

    c_post(I) = -5257.3 I^2 + 7671.5 I + 3203.3                      (N·s/m)
    F_y(I)    = -13417 I^4 + 25233 I^3 - 17787 I^2 + 6145.8 I + 1.33  (N)
    c_pre = 55.76 kN·s/m,  K_f = 1.29 MN/m,  M_f = 1.5 kg  (constant)

Dynamics (topology of Sims et al. [113], not printed in the thesis; chosen here): the fluid
compliance K_f in series with a fluid mass M_f that drives the bi-viscous element::

    s   = x_d - x_f                     spring deflection (m), x_d the damper stroke
    F   = K_f * s                       force transmitted by the damper (N)
    M_f x_f'' = K_f * s - F_bv(x_f', I)

In steady flow ``F -> F_bv(v, I)``. Stiff (pre-yield pole ``M_f / c_pre`` ~ 27 us): backward
Euler in substeps, each solved exactly (``F_bv`` piecewise linear, increasing in ``x_f'``).

Motion ratio ``r``: ``x_d' = r v_rel``, ``F_d = r F`` at the wheel; ``r = 1`` (default) is a
vertical damper. The thesis's lumped models scale its oblique damper by 1500/3800 = 0.395
(r ~ 0.628) and do not say whether the MR force was scaled.

The laws that drive it through its current (thesis Sec 5.3; docs/control.md): ``passive_mr``
a constant current (the thesis's "passive MR" at 0 A, Fig 5.7a); TSS3 Karnopp switching,
``I_hard`` (0.6 A) where ``v_b * v_rel < 0``, else ``I_soft`` (0 A) (Sec 5.3.3); TSS2 the MR
force tracking the TSS1 force ``F* = c_{soft|hard} * v_rel`` by feedback on the current (Sec
5.3.2, Fig 5.6, after Sims et al. [118]; the loop is withheld in the thesis), chosen form with
the published gains B = 0.8, G = 0.001 A/N: ``I = sat_[0, I_max](G (|F*| - B |F_MR|))``,
``F_MR`` the damper's (fluid-spring) force, evaluated every substep (without fluid dynamics:
solved exactly). The model is integrated from the previous call to ``t``, the velocities
interpolated linearly, so the force returned is the damper's at ``t``; ``c_eff = r^2
c_post(I)``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from cosim.config import ConfigReader
from nodes.controller.base import Controller, ControlOutput
from nodes.controller.skyhook import skyhook_condition

#: Table 5.1 polynomial coefficients, highest power first (numpy.polyval order).
C_POST_POLY = (-5257.3, 7671.5, 3203.3)
F_Y_POLY = (-13417.0, 25233.0, -17787.0, 6145.8, 1.33)


@dataclass(frozen=True)
class MRParams:
    """MR damper parameters (thesis Table 5.1 unless noted): c_pre (N·s/m), K_f (N/m), M_f
    (kg), I_max (A, end of the fits' range), motion_ratio r (-, not in the thesis), dynamics
    (K_f/M_f integrated, else the static law), substep (s, not in the thesis), the Table 5.1
    polynomials in I (A), highest power first."""

    c_pre: float = 55760.0
    K_f: float = 1.29e6
    M_f: float = 1.5
    I_max: float = 0.6
    motion_ratio: float = 1.0
    dynamics: bool = True
    substep: float = 5e-5
    c_post_poly: tuple[float, ...] = C_POST_POLY
    F_y_poly: tuple[float, ...] = F_Y_POLY

    @classmethod
    def from_config(cls, cfg: Mapping[str, Any], prefix: str) -> MRParams:
        """Overrides from a scenario table (``[controller.damper]``); unknown keys are errors."""
        r = ConfigReader(cfg, prefix,
                         ("c_pre", "K_f", "M_f", "I_max", "motion_ratio", "dynamics", "substep"))
        d = cls()
        return replace(d,
            c_pre=r.number("c_pre", d.c_pre, lo=0.0, lo_open=True, unit="N·s/m"),
            K_f=r.number("K_f", d.K_f, lo=0.0, lo_open=True, unit="N/m"),
            M_f=r.number("M_f", d.M_f, lo=0.0, lo_open=True, unit="kg"),
            I_max=r.number("I_max", d.I_max, lo=0.0, hi=0.6, lo_open=True, unit="A"),
            motion_ratio=r.number("motion_ratio", d.motion_ratio, lo=0.0, lo_open=True),
            dynamics=r.boolean("dynamics", d.dynamics),
            substep=r.number("substep", d.substep, lo=0.0, hi=1e-3, lo_open=True, unit="s"))


def c_post(I: np.ndarray | float, p: MRParams = MRParams()) -> np.ndarray:
    """Post-yield damping c_post(I) (N·s/m) of Table 5.1, damper frame."""
    return np.polyval(p.c_post_poly, np.asarray(I, dtype=float))


def yield_force(I: np.ndarray | float, p: MRParams = MRParams()) -> np.ndarray:
    """Yield force F_y(I) (N) of Table 5.1, damper frame."""
    return np.polyval(p.F_y_poly, np.asarray(I, dtype=float))


def bi_viscous_force(v: np.ndarray | float, I: np.ndarray | float,
                     p: MRParams = MRParams()) -> np.ndarray:
    """Static bi-viscous force F_bv(v, I) (N) at damper velocity v (m/s), damper frame."""
    v = np.asarray(v, dtype=float)
    cp, Fy, vy = knee(I, p)
    return np.where(np.abs(v) <= vy, p.c_pre * v, Fy * np.sign(v) + cp * v)


def knee(I: np.ndarray | float, p: MRParams = MRParams()
         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(c_post in N·s/m, F_y in N, knee velocity v_y = F_y / (c_pre - c_post) in m/s) at the
    current I (A), damper frame."""
    cp, Fy = c_post(I, p), yield_force(I, p)
    return cp, Fy, Fy / (p.c_pre - cp)


#: A current schedule inside one communication step: (fraction of the step in (0, 1],
#: damper force at the wheel before the substep (N)) -> current (A) per corner.
CurrentFn = Callable[[float, np.ndarray], np.ndarray]


class MRDamper:
    """MR damper of ``n`` corners with fluid dynamics, in the controller's wheel frame.

    :meth:`advance` once per communication step: v_rel interpolated linearly inside the step,
    the current recomputed every substep (the thesis's Simulink block ran at its finer rate).
    """

    def __init__(self, n: int, params: MRParams = MRParams()) -> None:
        self.p = params
        self.n = n
        self.s = np.zeros(n)  # spring deflection (m), damper frame
        self.v_f = np.zeros(n)  # fluid-mass velocity (m/s), damper frame
        self.I = np.zeros(n)  # current applied in the last substep (A)
        self._static_F = np.zeros(n)  # force at the wheel when dynamics is off (N)

    def static_force(self, v_rel: np.ndarray | float, I: np.ndarray | float) -> np.ndarray:
        """Steady-flow force at the wheel (N): ``r * F_bv(r * v_rel, I)``."""
        r = self.p.motion_ratio
        return r * bi_viscous_force(r * np.asarray(v_rel, dtype=float), I, self.p)

    @property
    def force(self) -> np.ndarray:
        """Current damper force at the wheel (N), on the body upward positive."""
        if not self.p.dynamics:
            return self._static_F
        return self.p.motion_ratio * self.p.K_f * self.s

    def c_eff(self, I: np.ndarray | float) -> np.ndarray:
        """Post-yield damping at the wheel, ``r^2 c_post(I)`` (N·s/m): the linearisation given
        to the plant (the pre-yield slope c_pre acts only through the stiff fluid spring)."""
        return self.p.motion_ratio**2 * c_post(I, self.p)

    def start(self, v_rel: np.ndarray, I: np.ndarray) -> np.ndarray:
        """Put the fluid in steady flow at ``v_rel`` (m/s) and current ``I`` (A); return force."""
        I = np.clip(np.broadcast_to(np.asarray(I, dtype=float), (self.n,)), 0.0, self.p.I_max)
        v_d = self.p.motion_ratio * np.asarray(v_rel, dtype=float)
        self.v_f = v_d.copy()
        self.s = bi_viscous_force(v_d, I, self.p) / self.p.K_f
        self.I = I.copy()
        self._static_F = self.static_force(v_rel, I)
        return self.force

    def advance(self, v_rel0: np.ndarray, v_rel1: np.ndarray, duration: float,
                current: CurrentFn) -> np.ndarray:
        """Integrate ``duration`` (s), v_rel linear from v_rel0 to v_rel1; the force at the
        wheel (N) at the end."""
        p = self.p
        if not p.dynamics or duration <= 0.0:
            I = self._current(current, 1.0, self.force)
            self._static_F = self.static_force(v_rel1, I)
            return self.force
        m = max(1, int(np.ceil(duration / p.substep - 1e-9)))
        dt = duration / m
        r = p.motion_ratio
        a = p.M_f / dt + p.K_f * dt  # BE left-hand side without the dashpot
        for j in range(1, m + 1):
            frac = j / m
            I = self._current(current, frac, self.force)
            v_d = r * (v_rel0 + frac * (v_rel1 - v_rel0))
            cp, Fy, vy = knee(I, p)
            rhs = p.M_f / dt * self.v_f + p.K_f * (self.s + dt * v_d)
            v_pre = rhs / (a + p.c_pre)
            v_post = (rhs - Fy * np.sign(rhs)) / (a + cp)
            v_new = np.where(np.abs(v_pre) <= vy, v_pre, v_post)
            self.s = self.s + dt * (v_d - v_new)
            self.v_f = v_new
        return self.force

    def _current(self, current: CurrentFn, frac: float, F_now: np.ndarray) -> np.ndarray:
        I = np.asarray(current(frac, F_now), dtype=float)
        I = np.clip(np.broadcast_to(I, (self.n,)), 0.0, self.p.I_max)
        self.I = I
        return I


# ------------------------------------------------------------------ the MR laws


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
        return np.full(self.n, np.nan), skyhook_condition(v_b, v_rel)

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
        """``sat_[0, I_max](G (|F*| - B |F_MR|))`` (A), F_MR the damper's force (N)."""
        F_star = self.f_star(v_b, v_rel)
        if not self.damper.p.dynamics:
            return self._solve_static(F_star, v_rel)
        return np.clip(self.G * (np.abs(F_star) - self.B * np.abs(F_mr)), 0.0,
                       self.damper.p.I_max)

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
