"""Sampled designs over parameter ranges (``[sweep.design]``, docs/sweeps.md): Latin
hypercube, Sobol' sequence (``scipy.stats.qmc``), Saltelli's (SALib), seeded. The design is one
sweep axis, ``sample`` (``s000``, ...), each point carrying its ranged keys' values as
parameters (rounded to 6 significant digits: the run gets exactly those).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from cosim.errors import ScenarioError

METHODS = ("lhs", "sobol", "saltelli")
DESIGN_KEYS = ("method", "n", "seed", "ranges")
AXIS = "sample"


@dataclass
class Range:

    key: str
    low: float
    high: float
    scale: str = "linear"


@dataclass
class Design:

    method: str
    n: int
    seed: int
    ranges: list[Range]
    values: np.ndarray  # (points, parameters), in the parameters' own units

    @property
    def keys(self) -> list[str]:
        return [r.key for r in self.ranges]


def _number(where: str, v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise ScenarioError(where, v, "a finite number")
    return float(v)


def _range(where: str, key: str, spec: Any) -> Range:
    scale = "linear"
    bounds = spec
    if isinstance(spec, dict):
        extra = set(spec) - {"range", "scale"}
        if extra:
            raise ScenarioError(f"{where}.{sorted(extra)[0]}", spec[sorted(extra)[0]],
                                "range or scale")
        bounds, scale = spec.get("range"), spec.get("scale", "linear")
        if scale not in ("linear", "log"):
            raise ScenarioError(f"{where}.scale", scale, "\"linear\" or \"log\"")
    if not isinstance(bounds, list) or len(bounds) != 2:
        raise ScenarioError(where, spec, "[low, high] or { range = [low, high], scale = "
                            "\"linear\"|\"log\" }")
    lo, hi = _number(where, bounds[0]), _number(where, bounds[1])
    if not lo < hi:
        raise ScenarioError(where, bounds, "low < high")
    if scale == "log" and lo <= 0:
        raise ScenarioError(where, bounds, "low > 0 for a log scale")
    return Range(key, lo, hi, scale)


def parse_design(spec: Any, check_key: Any) -> Design:
    """Read and sample ``[sweep.design]``; ScenarioError naming the key."""
    where = "sweep.design"
    if not isinstance(spec, dict):
        raise ScenarioError(where, spec, "a table with method, n, seed and ranges")
    for k in spec:
        if k not in DESIGN_KEYS:
            raise ScenarioError(f"{where}.{k}", spec[k], "one of " + ", ".join(DESIGN_KEYS))
    method = spec.get("method", "lhs")
    if method not in METHODS:
        raise ScenarioError(f"{where}.method", method, "one of " + ", ".join(METHODS))
    n, seed = spec.get("n"), spec.get("seed", 0)
    if isinstance(n, bool) or not isinstance(n, int) or n < 2:
        raise ScenarioError(f"{where}.n", n, "an integer >= 2")
    if method in ("sobol", "saltelli") and n & (n - 1):
        raise ScenarioError(f"{where}.n", n, "a power of 2 for a Sobol' sequence (its "
                            "balance properties hold only then), e.g. 16 or 32")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ScenarioError(f"{where}.seed", seed, "an integer >= 0")
    raw = spec.get("ranges")
    if not isinstance(raw, dict) or not raw:
        raise ScenarioError(f"{where}.ranges", raw, "a table of dotted keys and [low, high]")
    ranges = []
    for key, r in raw.items():
        check_key(f"{where}.ranges", key, 0.0)
        ranges.append(_range(f"{where}.ranges.{key}", key, r))
    unit = _unit_samples(method, n, seed, len(ranges), ranges)
    values = np.empty_like(unit)
    for j, r in enumerate(ranges):
        lo, hi = (math.log10(r.low), math.log10(r.high)) if r.scale == "log" else (r.low, r.high)
        x = lo + unit[:, j] * (hi - lo)
        values[:, j] = [float(f"{10.0 ** v if r.scale == 'log' else v:.6g}") for v in x]
    return Design(method, n, seed, ranges, values)


def _unit_samples(method: str, n: int, seed: int, d: int, ranges: list[Range]) -> np.ndarray:
    from scipy.stats import qmc

    if method == "lhs":
        return qmc.LatinHypercube(d=d, seed=seed).random(n)
    if method == "sobol":
        return qmc.Sobol(d=d, scramble=True, seed=seed).random_base2(int(math.log2(n)))
    from SALib.sample import sobol as salib_sobol

    unit_problem = {"num_vars": d, "names": [r.key for r in ranges], "bounds": [[0, 1]] * d}
    return salib_sobol.sample(unit_problem, n, calc_second_order=False, scramble=True, seed=seed)


def design_axis(design: Design) -> tuple[list[str], list[dict[str, Any]]]:
    width = max(3, len(str(len(design.values) - 1)))
    labels = [f"s{i:0{width}d}" for i in range(len(design.values))]
    overrides = [{k: float(v) for k, v in zip(design.keys, row, strict=True)}
                 for row in design.values]
    return labels, overrides
