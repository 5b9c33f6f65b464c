"""Build a scenario's controller: ``build_controller(cfg, n_corners, h)`` from its
``[controller]`` table, and the laws that need a class.

Every law is registered by name in :mod:`nodes.controller.registry`: most are one function
each (``@control_law``, beside their numerics: ``passive`` in dampers.py, ``tss1`` /
``skyhook_on_off``, ``skyhook``, ``skyhook_no_jerk`` in skyhook.py, ``groundhook``,
``groundhook_on_off`` in groundhook.py, ``hybrid`` in hybrid.py); the laws below need state or
substeps and register their builder (``@law_builder``): ``passive_curve``, ``passive_mr``,
``tss2``, ``tss3``, ``pnr`` / ``tss1_pnr``; ``fmu`` (an FMI co-simulation FMU) is in fmu.py.
``python3 -m nodes.controller.registry`` lists them all with their keys; docs/control.md
has the table with defaults and thesis sources.

Every law also accepts ``velocity`` ["relative" | "damper"]: "damper" makes the law use the
plant's ``v_damper`` (damper compression velocity, m/s, published by the double-wishbone
corner) instead of ``v_w - v_b``; see :mod:`nodes.controller.base`.

MR overrides (``damper`` table): c_pre, K_f, M_f, I_max, motion_ratio, dynamics, substep —
see :class:`nodes.controller.mr_damper.MRParams`.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from cosim.config import ConfigReader
from cosim.errors import ScenarioError
from nodes.controller.base import (
    VELOCITY_SOURCES,
    Controller,
    ControlOutput,
    body_scalar,
)
from nodes.controller.dampers import PassiveCurve
from nodes.controller.full_vehicle import pnr_select
from nodes.controller.mr_damper import MRParams
from nodes.controller.mr_laws import TSS2, TSS3, PassiveMR
from nodes.controller.registry import LAWS, PRESETS, discover, law_builder, lookup

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


class PitchRoll(Controller):
    """TSS1 PnR on a full vehicle (thesis Sec 5.4.4): minimum-product choice among the 16
    soft/hard combinations, see :mod:`nodes.controller.full_vehicle`.

    Angular accelerations: ``angular_acc = "rates"`` differentiates the body rates
    ``w_pitch``/``w_roll`` over the call interval (0 at the first call);
    ``"corners"`` uses Eqs 5.4/5.5 with the per-corner body accelerations ``a_b`` (m/s²,
    must be in the state) and the ``wheelbase``/``track`` (m).
    """

    law = "pnr"

    def __init__(
        self,
        n_corners: int,
        h: float,
        c_soft: float,
        c_hard: float,
        angular_acc: str,
        wheelbase: float,
        track: float,
    ) -> None:
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
                raise ValueError(
                    "controller state has no 'a_b' (angular_acc = 'corners')"
                ) from None
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
        return ControlOutput(
            F_d=F,
            c_eff=c,
            extra={
                "state": (c == self.c_hard).astype(float),
                "mp": np.full(self.n, float(n + 1)),
                "theta_dd": np.full(self.n, theta_dd),
                "phi_dd": np.full(self.n, phi_dd),
            },
        )


# --------------------------------------------------------------------------- builders

_MR_KEYS = ("damper",)
_SH = ("preset", "c_soft", "c_hard")


def _soft_hard(r: ConfigReader, soft: str = "c_soft", hard: str = "c_hard") -> tuple[float, float]:
    preset = r.choice("preset", sorted(PRESETS), "lumped")
    d_soft, d_hard = PRESETS[preset]
    c_soft = r.number(soft, d_soft, lo=0.0, unit="N·s/m")
    c_hard = r.number(hard, d_hard, lo=0.0, unit="N·s/m")
    if c_hard < c_soft:
        raise ScenarioError(r.key(hard), c_hard, f"a number >= {soft} ({c_soft:g}) N·s/m")
    return c_soft, c_hard


def _mr_params(r: ConfigReader) -> MRParams:
    return MRParams.from_config(r.table("damper"), r.key("damper"))


@law_builder("passive_curve", ("curve", "points"))
def _passive_curve(r: ConfigReader, n: int, h: float) -> Controller:
    """Passive damper on a force-velocity curve (CSV path or points)."""
    if r.has("curve") == r.has("points"):
        raise ScenarioError(
            r.key("curve"),
            r.cfg.get("curve"),
            "either 'curve' (a CSV path) or 'points' ([[v_rel, F_d], ...]), not both",
        )
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
    c_soft, c_hard = _soft_hard(r)
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
        raise ScenarioError(
            r.key("law"),
            r.cfg.get("law"),
            f"a per-corner law: 'pnr' needs a full vehicle (4 corners), this model has {n}",
        )
    c_soft, c_hard = _soft_hard(r)
    source = r.choice("angular_acc", ("rates", "corners"), "rates")
    wheelbase = track = float("nan")
    if source == "corners":
        wheelbase = r.number("wheelbase", lo=0.0, lo_open=True, unit="m")
        track = r.number("track", lo=0.0, lo_open=True, unit="m")
    elif r.has("wheelbase") or r.has("track"):
        key = "wheelbase" if r.has("wheelbase") else "track"
        raise ScenarioError(r.key(key), r.cfg[key], "no value unless angular_acc = 'corners'")
    return PitchRoll(n, h, c_soft, c_hard, source, wheelbase, track)


def build_controller(
    cfg: Mapping[str, Any], n_corners: int, h: float, key_prefix: str = "controller"
) -> Controller:
    """Build the controller a scenario's ``[controller]`` table asks for.

    Args:
        cfg: the table, e.g. ``{"law": "tss1", "c_soft": 1500, "c_hard": 2368}``.
        n_corners: 1 (quarter car) or 4 (full vehicle: FL, FR, RL, RR).
        h: communication step (s).
        key_prefix: dotted path of the table, used in error messages.

    Raises:
        ScenarioError: unknown law, unknown key, or a bad value (names the dotted key);
            ``law`` may be a registered name or ``"package.module:function"``.
        InputFileError: a malformed damper-curve CSV.
    """
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
