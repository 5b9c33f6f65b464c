"""Passive damper models and the semi-active clipping every variable damper obeys.

Convention (see :mod:`nodes.controller.base`): ``v_rel = v_w - v_b`` (m/s, compression
positive); ``F_d`` is the force on the body, upward positive (N).

* :func:`passive` — ``F_d = c * v_rel`` (thesis Table 4.3: c = 1500 N·s/m lumped,
  Table 4.2: 3800 N·s/m realistic).
* :class:`PassiveCurve` — a measured force-velocity curve, piecewise linear, with different
  bump (compression, v_rel > 0) and rebound (v_rel < 0) branches; read from CSV by
  :func:`load_curve_csv`.
* :func:`semi_active_force` — realise a demanded force with a variable damper whose
  coefficient lies in ``[c_min, c_max]``: the result is always ``c * v_rel`` with ``c`` in that
  range, so ``F_d * v_rel >= 0`` (no energy input) whatever is demanded.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from cosim.errors import InputFileError
from cosim.safe_open import read_user_text
from nodes.controller.registry import Param, control_law


@control_law("passive")
def passive(v_rel: np.ndarray | float, *, c: float = Param(1500.0, lo=0.0, unit="N·s/m")
            ) -> tuple[np.ndarray, float]:
    """Linear passive damper F_d = c v_rel (Table 4.3).

    Force on the body (N), ``c`` >= 0 (N·s/m); (F_d, c)."""
    return c * np.asarray(v_rel, dtype=float), c


def two_state_force(
    hard: np.ndarray, v_rel: np.ndarray, c_soft: float, c_hard: float
) -> tuple[np.ndarray, np.ndarray]:
    """Two-state damper: ``c = c_hard`` where ``hard`` else ``c_soft``; (F_d = c v_rel in N, c)."""
    c = np.where(hard, c_hard, c_soft)
    return c * np.asarray(v_rel, dtype=float), c


def semi_active_force(
    F_demand: np.ndarray, v_rel: np.ndarray, c_min: float, c_max: float
) -> tuple[np.ndarray, np.ndarray]:
    """(F_d in N, c in N·s/m): the force closest to ``F_demand`` (N) of a damper with
    ``c_min <= c <= c_max``. A non-dissipative demand (``F_demand * v_rel <= 0``) and
    ``v_rel == 0`` get ``c_min``; else ``c = F_demand / v_rel`` clipped to the range."""
    F_demand = np.asarray(F_demand, dtype=float)
    v_rel = np.asarray(v_rel, dtype=float)
    dissipative = F_demand * v_rel > 0.0
    safe_v = np.where(dissipative, v_rel, 1.0)
    c = np.where(dissipative, np.clip(F_demand / safe_v, c_min, c_max), c_min)
    return c * v_rel, c


class PassiveCurve:
    """Piecewise-linear passive damper ``F_d = f(v_rel)`` through the points ``v`` (m/s,
    strictly increasing), ``F`` (N, ``F * v >= 0``), the origin added, end segments extended;
    bump (v_rel > 0) and rebound branches independent. ``source`` names them in errors."""

    def __init__(self, v: Sequence[float] | np.ndarray, F: Sequence[float] | np.ndarray,
                 source: str = "<points>") -> None:
        v_arr = np.asarray(v, dtype=float)
        F_arr = np.asarray(F, dtype=float)
        problem = _curve_problem(v_arr, F_arr)
        if problem is not None:
            raise InputFileError(source, problem[0], problem[1])
        if not np.any(v_arr == 0.0):
            k = int(np.searchsorted(v_arr, 0.0))
            v_arr = np.insert(v_arr, k, 0.0)
            F_arr = np.insert(F_arr, k, 0.0)
        self.v = v_arr
        self.F = F_arr
        self.slopes = np.diff(F_arr) / np.diff(v_arr)
        self.source = source

    def _segment(self, v_rel: np.ndarray | float) -> np.ndarray:
        x = np.asarray(v_rel, dtype=float)
        return np.clip(np.searchsorted(self.v, x, side="right") - 1, 0, len(self.slopes) - 1)

    def force(self, v_rel: np.ndarray | float) -> np.ndarray:
        """Force on the body (N) at relative velocity ``v_rel`` (m/s)."""
        seg = self._segment(v_rel)
        return self.F[seg] + self.slopes[seg] * (np.asarray(v_rel, dtype=float) - self.v[seg])

    def slope(self, v_rel: np.ndarray | float) -> np.ndarray:
        """Local dF_d/dv_rel (N·s/m) of the segment containing ``v_rel``."""
        return self.slopes[self._segment(v_rel)]

    @classmethod
    def from_csv(cls, path: str | Path) -> PassiveCurve:
        """Read a curve from CSV; see :func:`load_curve_csv`."""
        v, F = load_curve_csv(path)
        return cls(v, F, source=str(path))


def _curve_problem(v: np.ndarray, F: np.ndarray) -> tuple[str, int | None] | None:
    """What is wrong with curve points, with the 1-based point index, or None."""
    if v.ndim != 1 or v.shape != F.shape:
        return "velocity and force lists must have the same length", None
    if v.size < 2:
        return f"a damper curve needs at least 2 points, got {v.size}", None
    for i in range(v.size):
        if not (math.isfinite(v[i]) and math.isfinite(F[i])):
            return f"point {i + 1} is not finite", i + 1
        if i and v[i] <= v[i - 1]:
            return f"velocities must be strictly increasing (point {i + 1}: {v[i]:g})", i + 1
        if F[i] * v[i] < 0.0 or (v[i] == 0.0 and F[i] != 0.0):
            return (f"point {i + 1} (v={v[i]:g} m/s, F={F[i]:g} N) is not dissipative: the force"
                    " must have the sign of the velocity (compression positive)", i + 1)
    return None


def load_curve_csv(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Read a damper curve: CSV ``v_rel`` (m/s, compression positive), ``F_d`` (N), velocities
    strictly increasing; blank and ``#`` lines ignored, a first non-numeric line is a header.
    InputFileError names the file and the 1-based line."""
    p = Path(path)
    text = read_user_text(p, "curve", "controller.curve")
    v: list[float] = []
    F: list[float] = []
    lines: list[int] = []
    seen_data = False
    for lineno, row in enumerate(csv.reader(text.splitlines()), start=1):
        cells = [c.strip() for c in row]
        if not cells or all(c == "" for c in cells) or cells[0].startswith("#"):
            continue
        try:
            values = [float(c) for c in cells if c != ""]
        except ValueError:
            if not seen_data and not v:
                seen_data = True  # header line
                continue
            raise InputFileError(str(p), f"not a number in {row!r}", lineno) from None
        seen_data = True
        if len(values) != 2:
            raise InputFileError(str(p), f"expected 2 columns (v_rel m/s, F_d N), got "
                                 f"{len(values)}", lineno)
        v.append(values[0])
        F.append(values[1])
        lines.append(lineno)
    va, Fa = np.asarray(v), np.asarray(F)
    problem = _curve_problem(va, Fa)
    if problem is not None:
        msg, idx = problem
        raise InputFileError(str(p), msg, lines[idx - 1] if idx is not None else None)
    return va, Fa
