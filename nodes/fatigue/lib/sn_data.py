"""S-N curves given as data: a table of (N, S) points or an nCode-style segment curve.

Both become a :class:`TabulatedSN`: log-log straight lines between points (N cycles, S the
fully reversed stress amplitude in Pa, R = -1), used exactly where :class:`SNCurve` is (the
damage of :mod:`damage` calls ``with_endurance(mode).reversals(σar)``; lives in reversals
2N = 2 x cycles).

* **Point table** ``[[N1, S1], [N2, S2], ...]``, N strictly increasing, S strictly
  decreasing (``stress = "range"`` if the S column is ranges: halved). Above the first point
  the first segment is continued; the last point is the knee (N_D, Se): below Se the
  scenario's endurance rule ("haibach": slope 2k - 1, k the last segment's slope;
  "elementary": no damage; "none": the last segment continued).
* **nCode segments** (nCode DesignLife's "standard" S-N curve): SRI1 = the stress **range**
  intercept at N = 1 cycle, b1 the first exponent (S = SRI1 N^b1 up to the transition life
  Nc1), b2 the exponent beyond Nc1 (b2 = 0: flat, no damage below). The curve itself says
  what happens beyond the knee, so the endurance rule is not applied to it.

An equivalent Basquin line σa = σ'f (2N)^b with knee (N_D, Se) is the table
[[1, σ'f 2^b], [N_D, σ'f (2 N_D)^b]] or the segments SRI1 = 2 σ'f 2^b, b1 = b, Nc1 = N_D,
b2 = -1/(2k - 1) for Haibach (0 for elementary), k = -1/b (tested: same damage).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from .life_models import ENDURANCE_MODES, below_knee


@dataclass(frozen=True)
class TabulatedSN:
    """A log-log piecewise-linear S-N curve (module docstring). ``n_cycles``, ``s_amp`` (Pa):
    the points; ``tail_b``: exponent (in cycles) beyond the last point, or None for the
    ``endurance`` rule."""

    n_cycles: tuple[float, ...]
    s_amp: tuple[float, ...]
    endurance: str = "haibach"
    tail_b: float | None = None
    name: str = "S-N curve from data"
    meta: Mapping = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        n = np.asarray(self.n_cycles, dtype=float)
        s = np.asarray(self.s_amp, dtype=float)
        if n.ndim != 1 or n.size < 2 or n.size != s.size:
            raise ValueError("an S-N table needs at least two (N, S) points")
        if not (np.all(np.isfinite(n)) and np.all(np.isfinite(s)) and n[0] >= 0.5
                and np.all(s > 0)):
            raise ValueError("S-N points must be finite, N >= 0.5 cycles and S > 0 Pa")
        if np.any(np.diff(n) <= 0) or np.any(np.diff(s) >= 0):
            raise ValueError("S-N points need N strictly increasing and S strictly decreasing")
        if self.endurance not in ENDURANCE_MODES:
            raise ValueError(f"endurance must be one of {ENDURANCE_MODES}, "
                             f"got {self.endurance!r}")
        if self.tail_b is not None and not (np.isfinite(self.tail_b) and self.tail_b <= 0):
            raise ValueError(f"the tail exponent must be <= 0, got {self.tail_b!r}")

    # the SNCurve interface ------------------------------------------------------------
    @property
    def Se(self) -> float:
        """The knee's amplitude (the last point), Pa."""
        return float(self.s_amp[-1])

    @property
    def knee_reversals(self) -> float:
        return 2.0 * float(self.n_cycles[-1])

    @property
    def b(self) -> float:
        """Exponent of the last segment (S ∝ N^b)."""
        ln, ls = np.log(self.n_cycles[-2:]), np.log(self.s_amp[-2:])
        return float((ls[1] - ls[0]) / (ln[1] - ln[0]))

    @property
    def k(self) -> float:
        """Slope k = -1/b of the last segment."""
        return -1.0 / self.b

    def with_endurance(self, endurance: str) -> TabulatedSN:
        return self if self.tail_b is not None else replace(self, endurance=endurance)

    def reversals(self, sar: np.ndarray) -> np.ndarray:
        """2N at equivalent amplitudes σar (Pa); σar <= 0 -> inf."""
        sar = np.asarray(sar, dtype=float)
        ln = np.log(np.asarray(self.n_cycles, dtype=float))
        ls = np.log(np.asarray(self.s_amp, dtype=float))
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            x = np.log(np.where(sar > 0, sar, 1.0))
            # np.interp needs increasing abscissae: interpolate ln N over -ln S
            lnN = np.interp(-x, -ls, ln)
            # above the first point: the first segment continued
            b0 = (ls[1] - ls[0]) / (ln[1] - ln[0])
            lnN = np.where(x > ls[0], ln[0] + (x - ls[0]) / b0, lnN)
            rev = 2.0 * np.exp(lnN)
            low = x < ls[-1]
            if self.tail_b is not None:
                tail = np.inf if self.tail_b == 0 else \
                    2.0 * np.exp(ln[-1] + (x - ls[-1]) / self.tail_b)
                rev = np.where(low, tail, rev)
            else:
                cont = 2.0 * np.exp(ln[-1] + (x - ls[-1]) / self.b)
                rev = np.where(low, cont, rev)
                rev = below_knee(rev, sar, self.Se, self.knee_reversals, self.k,
                                 self.endurance)
        return np.where(sar > 0.0, rev, np.inf)

    def stress(self, reversals: np.ndarray) -> np.ndarray:
        """σar (Pa) at lives 2N (for plots; the inverse of `reversals` where finite)."""
        n = 0.5 * np.asarray(reversals, dtype=float)
        ln = np.log(np.asarray(self.n_cycles, dtype=float))
        ls = np.log(np.asarray(self.s_amp, dtype=float))
        y = np.log(np.maximum(n, 1e-300))
        b0 = (ls[1] - ls[0]) / (ln[1] - ln[0])
        s = np.where(y < ln[0], ls[0] + b0 * (y - ln[0]), np.interp(y, ln, ls))
        beyond = y > ln[-1]
        tb = (self.tail_b if self.tail_b is not None  # the slope beyond the last point
              else -1.0 / (2.0 * self.k - 1.0) if self.endurance == "haibach"
              else 0.0 if self.endurance == "elementary" else self.b)
        s = np.where(beyond, ls[-1] + tb * (y - ln[-1]), s)
        return np.exp(s)

    def as_dict(self) -> dict:
        return {"name": self.name, "points_n_cycles": list(self.n_cycles),
                "points_s_amplitude_pa": list(self.s_amp), "Se_pa": self.Se,
                "knee_cycles": float(self.n_cycles[-1]), "k_last_segment": self.k,
                "endurance": "curve's own tail" if self.tail_b is not None
                else self.endurance, "tail_b": self.tail_b, **dict(self.meta)}


def points_curve(points: Sequence[Sequence[float]], stress: str = "amplitude",
                 endurance: str = "haibach", name: str = "S-N point table",
                 source: str = "") -> TabulatedSN:
    """A `TabulatedSN` from (N, S) points (S amplitudes, or ranges with ``stress="range"``)."""
    if stress not in ("amplitude", "range"):
        raise ValueError(f'stress must be "amplitude" or "range", got {stress!r}')
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError("points must be a list of [N, S] pairs")
    s = pts[:, 1] * (0.5 if stress == "range" else 1.0)
    return TabulatedSN(tuple(pts[:, 0].tolist()), tuple(s.tolist()), endurance, None, name,
                       {"sn_method": "points", "stress_column": stress, "source": source})


def ncode_curve(sri1: float, b1: float, nc1: float, b2: float = 0.0,
                name: str = "S-N segments (nCode style)", source: str = "") -> TabulatedSN:
    """A `TabulatedSN` from nCode's SRI1 (stress RANGE at 1 cycle, Pa), b1, Nc1, b2."""
    if not (np.isfinite(sri1) and sri1 > 0 and b1 < 0 and nc1 > 1 and b2 <= 0):
        raise ValueError(f"nCode curve needs SRI1 > 0, b1 < 0, Nc1 > 1, b2 <= 0; got "
                         f"{sri1}, {b1}, {nc1}, {b2}")
    s1 = 0.5 * sri1
    return TabulatedSN((1.0, float(nc1)), (s1, s1 * nc1**b1), "none", float(b2), name,
                       {"sn_method": "segments", "SRI1_pa": sri1, "b1": b1, "Nc1": nc1,
                        "b2": b2, "source": source})
