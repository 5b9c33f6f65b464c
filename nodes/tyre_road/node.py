"""The tyre/road node: road profile under each wheel and the vertical tyre force.

Every step k, from the plant's ``state`` (of step k, or k-1 in the parallel exchange), the road
height at each contact point of each wheel (:mod:`.wheel_paths`) and ``force``: F_t [N]
(absolute, compressive-positive, >= 0), k_t = dF_t/d(z_g - z_w) [N/m] for the plant's
coupling, z_g [m] (road height at the contact centre).

With ``[tyre] model = "magic_formula"`` (the four-corner vehicle): F_t from the point
contact as above, and the Magic Formula's road-plane Fx, Fy [N], Mz [N m] and the slips
kappa, alpha from the wheel kinematics the plant publishes (:mod:`.tyre_3d`); the road is
read where the wheels are (:class:`.wheel_paths.RoadPath`).
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from typing import Any

import numpy as np

from cosim import channels as ch
from cosim.errors import ScenarioError
from cosim.run_settings import RunSettings

from .config import build_road, build_tyre
from .tyre_3d import KIN_FIELDS, Tyre3D, build_tyre_3d, is_magic_formula
from .tyres import Tyre
from .wheel_paths import RoadPath, driver_radius, road_heights, road_heights_at

STATE = f"{ch.PLANT}/{ch.STATE}"


def wheel_geometry(info: dict[str, Any]) -> dict[str, Any]:
    """Static tyre load W [N] and wheel path facts per corner, from the plant's facts."""
    W = np.atleast_1d(np.asarray(info["static_tyre_load"], dtype=float))
    n = W.size
    return {"W": W, "wheel_x": np.asarray(info.get("wheel_x", [0.0] * n), dtype=float),
            "wheel_track": info.get("wheel_track", [1] * n),
            "corner_names": info.get("corner_names")}


class TyreRoad:
    """The tyre/road node as a stepped class (the shell: :func:`cosim.stepped.run_stepped`)."""

    FIELDS = {"plant/state": ("z_w",)}
    """What it reads of its input (the wheel's displacement)."""

    def __init__(self, scenario: dict[str, Any], start: dict[str, Any]) -> None:
        self.road = build_road(scenario["road"])
        self.tyre, self.mf = _tyres(scenario["tyre"])
        self._radius = driver_radius(scenario.get("vehicle", {}))
        self._origin: tuple[float, float] | None = None
        self._u: np.ndarray | None = None
        self._h = RunSettings.of(scenario).h
        self.geo = wheel_geometry(start["info"][ch.PLANT])
        self.offsets = np.asarray(self.tyre.contact_offsets, dtype=float)
        self.centre = int(np.argmin(np.abs(self.offsets)))

    STATE_ATTRS = ("_origin", "_u", "tyre", "mf")
    """What changes as the run goes (the Magic Formula's relaxation states, the road path's
    origin, the wheels' last stations); the rest is rebuilt the same from the scenario."""

    def checkpoint_state(self) -> dict[str, Any]:
        """The node's state at a step boundary, plain data (:mod:`cosim.plaindata`)."""
        return {k: copy.deepcopy(getattr(self, k)) for k in self.STATE_ATTRS}

    def restore_state(self, state: Mapping[str, Any]) -> None:
        """Continue from :meth:`checkpoint_state` (of a node built from the same scenario)."""
        for k in self.STATE_ATTRS:
            setattr(self, k, copy.deepcopy(state[k]))

    def step(self, k: int, t: float, inputs: Mapping[str, Mapping[str, np.ndarray]]
             ) -> dict[str, Any]:
        """F_t, k_t, z_g of step k from the plant's state (of step k, or k - 1: parallel)."""
        geo = self.geo
        if self.mf is not None:
            return self._step_3d(inputs[STATE])
        z_g = road_heights(self.road, t, geo["wheel_x"], geo["wheel_track"], self.offsets,
                           geo["corner_names"])
        F_t, k_eff = self.tyre.force(inputs[STATE]["z_w"], z_g, geo["W"])
        return {"F_t": F_t, "k_t": k_eff, "z_g": z_g[:, self.centre]}

    def _step_3d(self, st: Mapping[str, np.ndarray]) -> dict[str, Any]:
        """The Magic Formula's step: F_t (point contact) and Fx, Fy, Mz, kappa, alpha."""
        assert self.mf is not None
        try:
            kin = {k: np.asarray(st[k], dtype=float) for k in KIN_FIELDS}
        except KeyError as exc:
            raise ScenarioError("tyre.model", "magic_formula",
                                f"a vehicle whose plant/state carries the wheel kinematics "
                                f"({exc} is missing): full_vehicle_double_wishbone") from None
        if self._origin is None:  # the front axle's centre at the first step (FL, FR first)
            front = slice(0, min(2, kin["x_wc"].size))
            self._origin = (float(np.mean(kin["x_wc"][front])),
                            float(np.mean(kin["y_wc"][front])))
        path = RoadPath(self._origin, self._radius)
        self._u = path.station(kin["x_wc"], kin["y_wc"], self._u)
        geo = self.geo
        z_g = road_heights_at(self.road, self._u, geo["wheel_track"], self.offsets,
                              geo["corner_names"])
        F_t, k_eff = self.tyre.force(st["z_w"], z_g, geo["W"])
        f = self.mf.forces(kin, F_t, self._h)
        return {"F_t": F_t, "k_t": k_eff, "z_g": z_g[:, self.centre],
                **{k: f[k] for k in ("Fx", "Fy", "Mz", "kappa", "alpha")}}


def _tyres(cfg: Mapping[str, Any]) -> tuple[Tyre, Tyre3D | None]:
    """The vertical tyre of ``[tyre]`` and the Magic Formula's 3-D one (or None)."""
    return build_tyre_3d(cfg) if is_magic_formula(cfg) else (build_tyre(cfg), None)


def static_check(scenario: dict[str, Any]) -> float | None:
    """Preflight: build road and tyre (raises ScenarioError); returns the road's duration [s]."""
    if _tyres(scenario["tyre"])[1] is not None and scenario.get("run", {}).get("adaptive"):
        raise ScenarioError("run.h", "auto", "a fixed step with tyre.model = \"magic_formula\" "
                            "(its relaxation lengths are integrated with a fixed step)")
    return build_road(scenario["road"]).duration_s
