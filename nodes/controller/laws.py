"""Registry of control laws: ``build_controller(cfg, n_corners, h)`` from a scenario's
``[controller]`` table.

Laws (``law = "..."``) and their keys (defaults in brackets; "preset" defaults come from
``preset = "lumped"`` [1500 / 2368 N·s/m, Table 5.2 lumped QVM and 7-DOF FVM] or
``"realistic"`` [3800 / 6000 N·s/m, realistic QVM]):

==================== ==========================================================================
law                  keys
==================== ==========================================================================
passive              c [1500] N·s/m
passive_curve        curve: CSV path (v_rel m/s, F_d N) — or points = [[v, F], ...]
passive_mr           I [0.0] A; damper = {MR overrides}
tss1 (skyhook_on_off) preset, c_soft, c_hard
tss2                 preset, c_soft, c_hard, B [0.8], G [0.001] A/N; damper = {MR overrides}
tss3                 I_soft [0.0] A, I_hard [0.6] A; damper = {MR overrides}
skyhook              c_sky (required) N·s/m; preset, c_min [c_soft], c_max [c_hard]
skyhook_no_jerk      G (required) N·s²/m²; preset, c_min, c_max
groundhook           c_gnd (required) N·s/m; preset, c_min, c_max
groundhook_on_off    preset, c_soft, c_hard
hybrid               alpha (required, 0..1), G (required) N·s/m; preset, c_min, c_max
pnr (tss1_pnr)       preset, c_soft, c_hard, angular_acc ["rates" | "corners"], wheelbase, track
==================== ==========================================================================

Every law also accepts ``velocity`` ["relative" | "damper"]: "damper" makes the law use the
plant's ``v_damper`` (damper compression velocity, m/s, published by the double-wishbone
corner) instead of ``v_w - v_b``; see :mod:`nodes.controller.base`.

MR overrides (``damper`` table): c_pre, K_f, M_f, I_max, motion_ratio, dynamics, substep —
see :class:`nodes.controller.mr_damper.MRParams`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from cosim.errors import ScenarioError
from nodes.controller.base import (
    VELOCITY_SOURCES,
    ConfigReader,
    Controller,
    ControlOutput,
    body_scalar,
)
from nodes.controller.dampers import PassiveCurve
from nodes.controller.full_vehicle import pnr_select
from nodes.controller.groundhook import groundhook_continuous, groundhook_on_off
from nodes.controller.hybrid import hybrid
from nodes.controller.mr_damper import MRParams
from nodes.controller.mr_laws import TSS2, TSS3, PassiveMR
from nodes.controller.skyhook import skyhook_continuous, skyhook_no_jerk, skyhook_on_off

#: (c_soft, c_hard) in N·s/m of thesis Table 5.2.
PRESETS: dict[str, tuple[float, float]] = {
    "lumped": (1500.0, 2368.0),
    "realistic": (3800.0, 6000.0),
}


class Passive(Controller):
    """Linear passive damper ``F_d = c v_rel``; c in N·s/m."""

    law = "passive"

    def __init__(self, n_corners: int, h: float, c: float) -> None:
        super().__init__(n_corners, h)
        self.c = c

    def step(self, t: float, state: Mapping[str, np.ndarray]) -> ControlOutput:
        _, _, v_rel = self.corners(state)
        return ControlOutput(F_d=self.c * v_rel, c_eff=np.full(self.n, self.c))


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


class OnOff(Controller):
    """Two-state switching of the damping coefficient (TSS1 skyhook or groundhook)."""

    def __init__(self, n_corners: int, h: float, law: str, c_soft: float, c_hard: float) -> None:
        super().__init__(n_corners, h)
        self.law, self.c_soft, self.c_hard = law, c_soft, c_hard

    def step(self, t: float, state: Mapping[str, np.ndarray]) -> ControlOutput:
        v_b, v_w, v_rel = self.corners(state)
        if self.law == "groundhook_on_off":
            F, c, hard = groundhook_on_off(v_w, v_rel, self.c_soft, self.c_hard)
        else:
            F, c, hard = skyhook_on_off(v_b, v_rel, self.c_soft, self.c_hard)
        return ControlOutput(F_d=F, c_eff=c, extra={"state": hard.astype(float)})


class Clipped(Controller):
    """A continuous law realised by a variable damper (c_min <= c <= c_max).

    ``law_fn(v_b, v_w, v_rel) -> (F_d, c)``.
    """

    def __init__(
        self,
        n_corners: int,
        h: float,
        law: str,
        law_fn: Callable[[np.ndarray, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]],
    ) -> None:
        super().__init__(n_corners, h)
        self.law, self.law_fn = law, law_fn

    def step(self, t: float, state: Mapping[str, np.ndarray]) -> ControlOutput:
        v_b, v_w, v_rel = self.corners(state)
        F, c = self.law_fn(v_b, v_w, v_rel)
        return ControlOutput(F_d=F, c_eff=c, extra={"c": c})


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

Builder = Callable[[ConfigReader, int, float], Controller]


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


def _passive(r: ConfigReader, n: int, h: float) -> Controller:
    return Passive(n, h, r.number("c", 1500.0, lo=0.0, unit="N·s/m"))


def _passive_curve(r: ConfigReader, n: int, h: float) -> Controller:
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


def _passive_mr(r: ConfigReader, n: int, h: float) -> Controller:
    p = _mr_params(r)
    return PassiveMR(n, h, p, r.number("I", 0.0, lo=0.0, hi=p.I_max, unit="A"))


def _tss1(r: ConfigReader, n: int, h: float) -> Controller:
    return OnOff(n, h, "tss1", *_soft_hard(r))


def _groundhook_on_off(r: ConfigReader, n: int, h: float) -> Controller:
    return OnOff(n, h, "groundhook_on_off", *_soft_hard(r))


def _tss2(r: ConfigReader, n: int, h: float) -> Controller:
    c_soft, c_hard = _soft_hard(r)
    B = r.number("B", 0.8, lo=0.0, unit="(-)")
    G = r.number("G", 0.001, lo=0.0, lo_open=True, unit="A/N")
    return TSS2(n, h, _mr_params(r), c_soft, c_hard, B, G)


def _tss3(r: ConfigReader, n: int, h: float) -> Controller:
    p = _mr_params(r)
    I_soft = r.number("I_soft", 0.0, lo=0.0, hi=p.I_max, unit="A")
    I_hard = r.number("I_hard", p.I_max, lo=I_soft, hi=p.I_max, unit="A")
    return TSS3(n, h, p, I_soft, I_hard)


def _skyhook(r: ConfigReader, n: int, h: float) -> Controller:
    c_min, c_max = _soft_hard(r, "c_min", "c_max")
    c_sky = r.number("c_sky", lo=0.0, unit="N·s/m")
    return Clipped(
        n, h, "skyhook", lambda vb, vw, vr: skyhook_continuous(vb, vr, c_sky, c_min, c_max)
    )


def _skyhook_no_jerk(r: ConfigReader, n: int, h: float) -> Controller:
    c_min, c_max = _soft_hard(r, "c_min", "c_max")
    G = r.number("G", lo=0.0, unit="N·s²/m²")
    return Clipped(
        n, h, "skyhook_no_jerk", lambda vb, vw, vr: skyhook_no_jerk(vb, vr, G, c_min, c_max)
    )


def _groundhook(r: ConfigReader, n: int, h: float) -> Controller:
    c_min, c_max = _soft_hard(r, "c_min", "c_max")
    c_gnd = r.number("c_gnd", lo=0.0, unit="N·s/m")
    return Clipped(
        n, h, "groundhook", lambda vb, vw, vr: groundhook_continuous(vw, vr, c_gnd, c_min, c_max)
    )


def _hybrid(r: ConfigReader, n: int, h: float) -> Controller:
    c_min, c_max = _soft_hard(r, "c_min", "c_max")
    alpha = r.number("alpha", lo=0.0, hi=1.0)
    G = r.number("G", lo=0.0, unit="N·s/m")
    return Clipped(n, h, "hybrid", lambda vb, vw, vr: hybrid(vb, vw, alpha, G, c_min, c_max))


def _pnr(r: ConfigReader, n: int, h: float) -> Controller:
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


_MR_KEYS = ("damper",)
_SH = ("preset", "c_soft", "c_hard")
_CLIP = ("preset", "c_min", "c_max")

#: law name -> (builder, accepted keys besides "law")
LAWS: dict[str, tuple[Builder, tuple[str, ...]]] = {
    "passive": (_passive, ("c",)),
    "passive_curve": (_passive_curve, ("curve", "points")),
    "passive_mr": (_passive_mr, ("I", *_MR_KEYS)),
    "tss1": (_tss1, _SH),
    "skyhook_on_off": (_tss1, _SH),
    "tss2": (_tss2, (*_SH, "B", "G", *_MR_KEYS)),
    "tss3": (_tss3, ("I_soft", "I_hard", *_MR_KEYS)),
    "skyhook": (_skyhook, (*_CLIP, "c_sky")),
    "skyhook_no_jerk": (_skyhook_no_jerk, (*_CLIP, "G")),
    "groundhook": (_groundhook, (*_CLIP, "c_gnd")),
    "groundhook_on_off": (_groundhook_on_off, _SH),
    "hybrid": (_hybrid, (*_CLIP, "alpha", "G")),
    "pnr": (_pnr, (*_SH, "angular_acc", "wheelbase", "track")),
    "tss1_pnr": (_pnr, (*_SH, "angular_acc", "wheelbase", "track")),
}


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
        ScenarioError: unknown law, unknown key, or a bad value (names the dotted key).
        InputFileError: a malformed damper-curve CSV.
    """
    if n_corners < 1:
        raise ValueError(f"n_corners must be >= 1, got {n_corners}")
    if not h > 0.0:
        raise ValueError(f"communication step h must be > 0 s, got {h}")
    if not isinstance(cfg, Mapping):
        raise ScenarioError(key_prefix, cfg, "a table with a 'law' key")
    law = cfg.get("law")
    if law not in LAWS:
        raise ScenarioError(f"{key_prefix}.law", law, f"one of {sorted(LAWS)}")
    builder, keys = LAWS[law]
    reader = ConfigReader(cfg, key_prefix, ("law", "velocity", *keys))
    velocity = reader.choice("velocity", VELOCITY_SOURCES, "relative")
    controller = builder(reader, int(n_corners), float(h))
    controller.velocity = velocity
    return controller
