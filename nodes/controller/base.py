"""What every controller shares: the output record and the base class.

Sign convention (whole package), per corner:

* ``v_rel = v_w - v_b`` (m/s), positive in compression (wheel moving up toward the body);
* ``F_d`` (N) is the damper force **on the body, upward positive**; the wheel gets ``-F_d``;
* a passive linear damper gives ``F_d = c * v_rel``;
* a semi-active (dissipative) damper can only give ``F_d * v_rel >= 0``.

Damper velocity (``velocity = "damper"``): a plant with an oblique damper (the
double-wishbone corner) publishes ``v_damper`` (m/s, positive when it shortens) and applies
``F_d`` along the damper axis; every law then reads ``v_damper`` as ``v_rel`` (a physical
3800 N·s/m applies as is) and its slope goes back to the plant through the motion ratio
(:meth:`Controller.plant_slope`).

The thesis writes its laws with the extension-positive velocity ``z_b' - z_w'``; each law's
docstring gives the thesis form and its translation into the convention above.
"""

from __future__ import annotations

import copy
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cosim import plaindata

#: Values of the generic ``velocity`` key: which velocity the laws use as ``v_rel``.
VELOCITY_SOURCES = ("relative", "damper")
#: Below this |v_w - v_b| (m/s) the motion-ratio estimate is not updated (ill-conditioned).
RATIO_MIN_SPEED = 0.01
#: Extra keys present for a full vehicle (one value each, as length-1 arrays or scalars).
BODY_KEYS = ("v_heave", "w_pitch", "w_roll", "pitch", "roll")


@dataclass
class ControlOutput:
    """Per corner: ``F_d`` on the body, upward positive (N); ``c_eff`` = dF_d/dv_rel (N·s/m)
    for the plant's ``F ≈ F_d + c_eff (v_rel(t) - v_rel(t_k))``; ``extra`` channels to record
    (``I`` in A, ``state`` 1 = hard / 0 = soft, ``F_demand`` in N)."""

    F_d: np.ndarray
    c_eff: np.ndarray
    extra: dict[str, np.ndarray] = field(default_factory=dict)


class Controller(ABC):
    """Drives every corner, vectorised over ``n_corners`` (1, or 4: FL, FR, RL, RR); ``h``
    the communication step (s)."""

    #: registry name of the law (set by subclasses)
    law: str = ""
    #: the law integrates a state with the step ``h`` it was built with (an MR damper's fluid,
    #: a law function taking ``h`` or ``memory``, an FMU's communication step): it cannot run
    #: with ``run.h = "auto"`` (refused by the preflight)
    fixed_step: bool = False
    #: "relative" (v_rel = v_w - v_b) or "damper" (v_rel = the plant's v_damper); set by
    #: :func:`nodes.controller.laws.build_controller` from the ``velocity`` key.
    velocity: str = "relative"

    def __init__(self, n_corners: int, h: float) -> None:
        self.n = int(n_corners)
        self.h = float(h)
        self._ratio = np.ones(self.n)

    @abstractmethod
    def step(self, t: float, state: Mapping[str, np.ndarray]) -> ControlOutput:
        """Return the damper forces at time ``t`` (s) for the plant state at ``t``."""

    def close(self) -> None:
        """Release what the law holds outside Python (an FMU's instances); a no-op here."""
        return None

    def checkpoint_state(self) -> dict[str, Any]:
        """The law's whole internal state for a checkpoint: a deep copy of the attributes that
        are plain data (:mod:`cosim.plaindata`); the others (functions, registry spec) are
        rebuilt by the fresh instance and listed under ``rebuilt`` (none holds state:
        tests/controller/test_controller_checkpoint.py). The FMU law overrides this."""
        attrs: dict[str, Any] = {}
        rebuilt: list[str] = []
        for key, value in self.__dict__.items():
            try:
                plaindata.encode(value)
            except plaindata.PlainDataError:
                rebuilt.append(key)
                continue
            attrs[key] = copy.deepcopy(value)
        return {"law": self.law, "attrs": attrs, "rebuilt": rebuilt}

    def restore_state(self, state: dict[str, Any], t: float,
                      state_inputs: Mapping[str, np.ndarray]) -> None:
        """Put the law back into a :meth:`checkpoint_state` ``state`` (``t`` [s] and the plant's
        ``state_inputs`` at the checkpoint are for laws that must start something first)."""
        if state.get("law") != self.law:
            raise ValueError(f"checkpoint holds the state of law {state.get('law')!r}, "
                             f"not of {self.law!r}")
        self.__dict__.update(copy.deepcopy(state["attrs"]))

    def corners(self, state: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(v_b, v_w, v_rel) per corner (m/s); ``v_rel`` is ``v_w - v_b`` or ``v_damper``."""
        v_b = corner_array(state, "v_b", self.n)
        v_w = corner_array(state, "v_w", self.n)
        if self.velocity == "damper":
            return v_b, v_w, corner_array(state, "v_damper", self.n)
        return v_b, v_w, v_w - v_b

    def inputs(self, state: Mapping[str, Any], names: Sequence[str], **known: Any) -> list[Any]:
        """The signals ``names`` of the plant's ``state``: ``v_b``, ``v_w``, ``v_rel`` (m/s, of
        :meth:`corners`) and any other key per corner, the full vehicle's :data:`BODY_KEYS` as
        floats, the ``known`` ones as given."""
        v_b, v_w, v_rel = self.corners(state)
        known = {"v_b": v_b, "v_w": v_w, "v_rel": v_rel, **known}
        return [known[k] if k in known else body_scalar(state, k) if k in BODY_KEYS
                else corner_array(state, k, self.n) for k in names]

    def plant_slope(self, c_eff: np.ndarray, state: Mapping[str, Any]) -> np.ndarray:
        """The law's slope (N·s/m) as dF_d/d(v_w - v_b): for ``"damper"`` times the motion ratio
        v_damper / (v_w - v_b), updated when |v_w - v_b| > :data:`RATIO_MIN_SPEED` (else held;
        1.0 at first)."""
        if self.velocity != "damper":
            return c_eff
        v_rel = corner_array(state, "v_w", self.n) - corner_array(state, "v_b", self.n)
        v_d = corner_array(state, "v_damper", self.n)
        ok = np.abs(v_rel) > RATIO_MIN_SPEED
        self._ratio = np.where(ok, v_d / np.where(ok, v_rel, 1.0), self._ratio)
        return np.asarray(c_eff, dtype=float) * self._ratio


def corner_array(state: Mapping[str, Any], key: str, n: int) -> np.ndarray:
    """``state[key]`` as a float array of shape (n,); a scalar is broadcast."""
    try:
        raw = state[key]
    except KeyError:
        raise ValueError(f"controller state has no '{key}' (keys: {sorted(state)})") from None
    arr = np.asarray(raw, dtype=float).reshape(-1)
    if arr.size == 1 and n != 1:
        return np.full(n, float(arr[0]))
    if arr.size != n:
        raise ValueError(f"controller state '{key}' has {arr.size} values, expected {n}")
    return arr


def body_scalar(state: Mapping[str, Any], key: str) -> float:
    """A full-vehicle scalar (``w_pitch`` ...) given as a scalar or a length-1 array."""
    try:
        arr = np.asarray(state[key], dtype=float).reshape(-1)
    except KeyError:
        msg = f"controller state has no '{key}' (needed by a full-vehicle law)"
        raise ValueError(msg) from None
    if arr.size != 1:
        raise ValueError(f"controller state '{key}' has {arr.size} values, expected 1")
    return float(arr[0])
