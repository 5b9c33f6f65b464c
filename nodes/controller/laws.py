"""Build a scenario's controller: ``build_controller(cfg, n_corners, h)`` from its
``[controller]`` table, and the laws that need a class.

Most laws are one ``@control_law`` function beside their numerics (dampers.py, skyhook.py,
add.py); those below need state or substeps and register a builder
(``@law_builder``); ``fmu`` is in fmu.py. ``python3 -m nodes.controller.registry`` lists them
all; docs/control.md gives defaults and thesis sources. Every law also accepts ``velocity``
(:mod:`nodes.controller.base`); the MR laws a ``damper`` table (:class:`.mr_damper.MRParams`).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from cosim.config import ConfigReader
from cosim.errors import ScenarioError
from nodes.controller.base import VELOCITY_SOURCES, Controller, ControlOutput, body_scalar
from nodes.controller.dampers import PassiveCurve
from nodes.controller.mr_damper import TSS2, TSS3, MRParams, PassiveMR
from nodes.controller.registry import LAWS, PRESETS, discover, law_builder, lookup, soft_hard

__all__ = ["LAWS", "PRESETS", "build_controller"]


class PassiveCurveController(Controller):
    """Passive damper following a piecewise-linear force-velocity curve; ``c_eff`` is the
    slope of the segment in use."""

    law = "passive_curve"

    def __init__(self, n_corners: int, h: float, curve: PassiveCurve) -> None:
        super().__init__(n_corners, h)
        self.curve = curve

    def step(self, t: float, state: Mapping[str, np.ndarray]) -> ControlOutput:
        _, _, v_rel = self.corners(state)
        return ControlOutput(F_d=self.curve.force(v_rel), c_eff=self.curve.slope(v_rel))


#: (16, 4) bool: row n-1 is MPn, True = hard, columns FL, FR, RL, RR (binary n-1, FL = MSB).
COMBINATIONS = np.array([[(n >> (3 - i)) & 1 for i in range(4)] for n in range(16)], dtype=bool)


def pnr_select(v_rel: np.ndarray, c_soft: float, c_hard: float, theta_dd: float,
               phi_dd: float) -> tuple[int, np.ndarray, np.ndarray]:
    """(index n of MP(n+1), forces (4,) on the body in N, coefficients (4,) in N·s/m) of the
    minimum-product combination (:class:`PitchRoll`) from ``v_rel`` (m/s, FL, FR, RL, RR),
    ``c_soft``/``c_hard`` (N·s/m, Table 5.2: 1500 / 2368), ``theta_dd`` nose-up and ``phi_dd``
    left-up (rad/s²); ties: the lowest MP, so no angular acceleration: all soft."""
    forces = np.where(COMBINATIONS, c_hard, c_soft) * np.asarray(v_rel, dtype=float).reshape(4)
    fl, fr, rl, rr = forces.T
    if abs(theta_dd) > abs(phi_dd):
        products = (fl + fr - rl - rr) * theta_dd
    else:
        products = (fl + rl - fr - rr) * phi_dd
    n = int(np.argmin(products))
    return n, forces[n].copy(), np.where(COMBINATIONS[n], c_hard, c_soft).astype(float)


class PitchRoll(Controller):
    """Full-vehicle pitch-and-roll two-state controller, TSS1 PnR (thesis Sec 5.4.4, Eqs
    5.4-5.12, Table 5.2; after Nell & Steyn [20]).

    Each step, of the 16 soft/hard combinations MP1..MP16 of the dampers (FL, FR, RL, RR) with
    corner forces ``F_i = c_i * v_rel_i``, the one with the minimum product (MP) of the damper
    moment and the body angular acceleration is chosen: ``P_n = (F_FL + F_FR - F_RL - F_RR)_n *
    theta''`` if ``|theta''| > |phi''|`` (Eq 5.6/5.7), else ``(F_FL + F_RL - F_FR - F_RR)_n *
    phi''`` (Eq 5.8); ``theta''`` nose-**up** (Eq 5.4: ``(z_FL'' - z_RL'')/wheelbase``),
    ``phi''`` left-**up** (Eq 5.5: ``(z_FL'' - z_FR'')/track``), rad/s². ``F_i`` is the force on
    the body, upward positive, so the minimum is the combination whose moment most *opposes*
    the angular acceleration, the intent of [20] (the thesis's ``d_i = C v_rel`` with the
    opposite sign would aid the motion; docs/control.md).

    ``angular_acc = "rates"`` differentiates the ISO 8855 rates (``w_pitch`` about +y, nose
    down positive; ``w_roll`` about +x, left up positive: ``theta'' = -d(w_pitch)/dt``,
    ``phi'' = +d(w_roll)/dt``) over the call interval (0 at the first call); ``"corners"``
    uses Eqs 5.4/5.5 with ``a_b`` (m/s²) and the ``wheelbase``/``track`` (m)."""

    law = "pnr"

    def __init__(self, n_corners: int, h: float, c_soft: float, c_hard: float,
                 angular_acc: str, wheelbase: float, track: float) -> None:
        super().__init__(n_corners, h)
        self.c_soft, self.c_hard = c_soft, c_hard
        self.angular_acc, self.wheelbase, self.track = angular_acc, wheelbase, track
        self._prev: tuple[float, float, float] | None = None

    def accelerations(self, t: float, state: Mapping[str, np.ndarray]) -> tuple[float, float]:
        """(nose-up pitch, left-up roll) angular accelerations in rad/s²."""
        if self.angular_acc == "corners":
            try:
                a = np.asarray(state["a_b"], dtype=float).reshape(4)
            except KeyError:
                msg = "controller state has no 'a_b' (angular_acc = 'corners')"
                raise ValueError(msg) from None
            return (a[0] - a[2]) / self.wheelbase, (a[0] - a[1]) / self.track
        wp, wr = body_scalar(state, "w_pitch"), body_scalar(state, "w_roll")
        prev, self._prev = self._prev, (float(t), wp, wr)
        if prev is None or t <= prev[0]:
            return 0.0, 0.0
        dt = t - prev[0]
        return -(wp - prev[1]) / dt, (wr - prev[2]) / dt

    def step(self, t: float, state: Mapping[str, np.ndarray]) -> ControlOutput:
        _, _, v_rel = self.corners(state)
        theta_dd, phi_dd = self.accelerations(t, state)
        n, F, c = pnr_select(v_rel, self.c_soft, self.c_hard, theta_dd, phi_dd)
        return ControlOutput(F_d=F, c_eff=c, extra={
            "state": (c == self.c_hard).astype(float), "mp": np.full(self.n, float(n + 1)),
            "theta_dd": np.full(self.n, theta_dd), "phi_dd": np.full(self.n, phi_dd)})


# --------------------------------------------------------------------------- builders

_MR_KEYS = ("damper",)
_SH = ("preset", "c_soft", "c_hard")


def _mr_params(r: ConfigReader) -> MRParams:
    return MRParams.from_config(r.table("damper"), r.key("damper"))


@law_builder("passive_curve", ("curve", "points"))
def _passive_curve(r: ConfigReader, n: int, h: float) -> Controller:
    """Passive damper on a force-velocity curve (CSV path or points)."""
    if r.has("curve") == r.has("points"):
        raise ScenarioError(r.key("curve"), r.cfg.get("curve"), "either 'curve' (a CSV path) "
                            "or 'points' ([[v_rel, F_d], ...]), not both")
    if r.has("curve"):
        return PassiveCurveController(n, h, PassiveCurve.from_csv(Path(r.string("curve"))))
    pts = r.cfg["points"]
    try:
        arr = np.asarray(pts, dtype=float)
        ok = arr.ndim == 2 and arr.shape[1] == 2
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ScenarioError(r.key("points"), pts, "a list of [v_rel m/s, F_d N] pairs")
    return PassiveCurveController(n, h, PassiveCurve(arr[:, 0], arr[:, 1], source=r.key("points")))


@law_builder("passive_mr", ("I", *_MR_KEYS))
def _passive_mr(r: ConfigReader, n: int, h: float) -> Controller:
    """MR damper at a constant current I (thesis "passive MR", Fig 5.7a)."""
    p = _mr_params(r)
    return PassiveMR(n, h, p, r.number("I", 0.0, lo=0.0, hi=p.I_max, unit="A"))


@law_builder("tss2", (*_SH, "B", "G", *_MR_KEYS))
def _tss2(r: ConfigReader, n: int, h: float) -> Controller:
    """MR damper tracking the TSS1 force by current feedback (thesis Sec 5.3.2)."""
    c_soft, c_hard = soft_hard(r)
    B = r.number("B", 0.8, lo=0.0, unit="(-)")
    G = r.number("G", 0.001, lo=0.0, lo_open=True, unit="A/N")
    return TSS2(n, h, _mr_params(r), c_soft, c_hard, B, G)


@law_builder("tss3", ("I_soft", "I_hard", *_MR_KEYS))
def _tss3(r: ConfigReader, n: int, h: float) -> Controller:
    """Two-state skyhook switching the MR current (thesis Sec 5.3.3)."""
    p = _mr_params(r)
    I_soft = r.number("I_soft", 0.0, lo=0.0, hi=p.I_max, unit="A")
    I_hard = r.number("I_hard", p.I_max, lo=I_soft, hi=p.I_max, unit="A")
    return TSS3(n, h, p, I_soft, I_hard)


@law_builder("pnr", (*_SH, "angular_acc", "wheelbase", "track"), aliases=("tss1_pnr",))
def _pnr(r: ConfigReader, n: int, h: float) -> Controller:
    """Full-vehicle pitch-and-roll TSS1, minimum product of 16 combinations (Sec 5.4.4)."""
    if n != 4:
        raise ScenarioError(r.key("law"), r.cfg.get("law"), f"a per-corner law: 'pnr' needs a "
                            f"full vehicle (4 corners), this model has {n}")
    c_soft, c_hard = soft_hard(r)
    source = r.choice("angular_acc", ("rates", "corners"), "rates")
    wheelbase = track = float("nan")
    if source == "corners":
        wheelbase = r.number("wheelbase", lo=0.0, lo_open=True, unit="m")
        track = r.number("track", lo=0.0, lo_open=True, unit="m")
    elif r.has("wheelbase") or r.has("track"):
        key = "wheelbase" if r.has("wheelbase") else "track"
        raise ScenarioError(r.key(key), r.cfg[key], "no value unless angular_acc = 'corners'")
    return PitchRoll(n, h, c_soft, c_hard, source, wheelbase, track)


def build_controller(cfg: Mapping[str, Any], n_corners: int, h: float,
                     key_prefix: str = "controller") -> Controller:
    """The controller of the ``[controller]`` table ``cfg`` (dotted path ``key_prefix``) for
    ``n_corners`` (1, or 4: FL, FR, RL, RR) at the step ``h`` (s). ScenarioError naming the
    key for an unknown law or key or a bad value; InputFileError for a bad curve CSV."""
    if n_corners < 1:
        raise ValueError(f"n_corners must be >= 1, got {n_corners}")
    if not h > 0.0:
        raise ValueError(f"communication step h must be > 0 s, got {h}")
    if not isinstance(cfg, Mapping):
        raise ScenarioError(key_prefix, cfg, "a table with a 'law' key")
    spec = lookup(cfg.get("law"), f"{key_prefix}.law")
    reader = ConfigReader(cfg, key_prefix, ("law", "velocity", *spec.keys))
    velocity = reader.choice("velocity", VELOCITY_SOURCES, "relative")
    controller = spec.build(reader, int(n_corners), float(h))
    controller.velocity = velocity
    return controller


discover()  # every law of the package registered once this module is imported
