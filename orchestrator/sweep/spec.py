"""The sweep file: its keys, axes and points (``load_sweep``), point ids, TOML values for
``--set``, the preflight of every point's scenario (``validate_points``), and sampled designs
over parameter ranges (``[sweep.design]``: Latin hypercube, Sobol' sequence (``scipy.stats.qmc``),
Saltelli's (SALib), seeded): one sweep axis, ``sample`` (``s000``, ...), each point carrying its
ranged keys' values as parameters (rounded to 6 significant digits: the run gets exactly those).
"""

from __future__ import annotations

import copy
import hashlib
import itertools
import json
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cosim import keys
from cosim import scenario as sc
from cosim.config import ConfigReader
from cosim.errors import InputFileError, ScenarioError, SuscosimError
from cosim.keys import check_name
from cosim.safe_open import read_user_toml

SWEEP_KEYS = ("name", "base", "jobs", "fatigue", "grid", "set", "channels", "description",
              "design", "runs_dir", "fork_at")
DEFAULT_CHANNELS = ("plant/response/a_b", "plant/response/a_w", "tyre_road/force/F_t",
                    "controller/force/F_d", "plant/arm/ball_joint_z")
FATIGUE_COLUMNS = ("life_repeats", "life_km", "max_damage", "critical_node")
MAX_ID = 64
INVOCATION = keys.invocation_token()  # the random part of this process's run ids
RESERVED = ("base", "point", "status", "error", "wall_s", "steps_per_s", "n_steps", "run_dir",
            "worker", "sample", "fork_at", "parent", *FATIGUE_COLUMNS)


class SweepError(SuscosimError):
    exit_code = 2


@dataclass
class Axis:
    """One grid axis: a parameter name and, per value, its label and overrides."""

    name: str
    labels: list[Any]
    overrides: list[dict[str, Any]]
    bases: list[Path] | None = None  # the ``base`` axis: one scenario file per label
    params: list[dict[str, Any]] | None = None  # the design axis: per label, its parameters


@dataclass
class Point:
    index: int
    id: str
    params: dict[str, Any]
    base: Path
    overrides: dict[str, Any]
    n_steps: int = 0
    fingerprint: str = ""

    @property
    def run_id(self) -> str:
        """The point id and :data:`INVOCATION` (two sweeps on one router never share ids)."""
        return keys.unique_run_id(self.id, INVOCATION)

    def _assignments(self, run_id: str) -> list[str]:
        return [f"{k}={toml_value(v)}" for k, v in self.overrides.items()] + \
            [f"run.id={toml_value(run_id)}"]

    @property
    def set_args(self) -> list[str]:
        return self._assignments(self.run_id)

    @property
    def fingerprint_args(self) -> list[str]:
        """:attr:`set_args` with the point id as run id (the same in every invocation)."""
        return self._assignments(self.id)


@dataclass
class Sweep:
    """A parsed and checked sweep file (scenarios not yet validated)."""

    path: Path
    name: str
    bases: list[Path]
    axes: list[Axis]
    fixed: dict[str, Any]
    jobs: int
    fatigue: bool
    channels: list[str]
    raw_grid: dict[str, Any]
    points: list[Point] = field(default_factory=list)
    design: Design | None = None
    runs_dir: Path | None = None  # a shared folder for the run folders (else <out>/runs)
    fork_at: float | None = None  # [sweep] fork_at: the points fork from parents at T [s]
    fork: Any = None  # its plan (a .fork.ForkPlan), made by validate_points

    def run_dir(self, out: Path, p: Point) -> Path:
        return (self.runs_dir if self.runs_dir is not None else out / "runs") / p.id

    def run_dir_text(self, p: Point) -> str:
        return str(self.runs_dir / p.id) if self.runs_dir is not None else f"runs/{p.id}"


def toml_value(v: Any) -> str:
    """A Python value (from TOML) as a TOML inline value, for ``--set``."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, list | tuple):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{json.dumps(str(k))} = {toml_value(x)}"
                               for k, x in v.items()) + "}"
    raise TypeError(f"cannot write {type(v).__name__} as a TOML value")


def _slug(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int | float):
        return repr(v)
    if isinstance(v, str):
        s = re.sub(r"[^A-Za-z0-9_.]+", "_", v).strip("_.")
        return s or "x"
    return "h" + hashlib.sha1(json.dumps(v, sort_keys=True).encode()).hexdigest()[:8]


def point_id(name: str, labels: list[Any]) -> str:
    """``<name>-<value>-...``: ``[A-Za-z0-9_.-]``, at most 64 (longer: cut, then a hash)."""
    pid = "-".join([name, *(_slug(v) for v in labels)])
    if len(pid) > MAX_ID:
        digest = hashlib.sha1(json.dumps([name, labels], sort_keys=True,
                                         default=str).encode()).hexdigest()[:10]
        pid = pid[:MAX_ID - 11].rstrip("-_.") + "-" + digest
    return pid


def _check_override_key(where: str, key: Any, value: Any) -> None:
    if not isinstance(key, str) or not key:
        raise SweepError(f"{where}: override keys must be dotted scenario keys")
    parts = key.split(".")
    if not all(parts) or (len(parts) < 2 and not isinstance(value, dict)):
        raise ScenarioError(f"{where}.{key}", value,
                            "a dotted scenario key such as \"run.h\" (quoted in TOML), or a "
                            "section name with a table value")
    if parts[0] not in sc.SECTIONS:
        raise ScenarioError(f"{where}.{key}", value,
                            "a key in one of the sections " + ", ".join(sc.SECTIONS))


def _absolute_paths(overrides: dict[str, Any], folder: Path) -> dict[str, Any]:
    out = copy.deepcopy(overrides)
    for s, k in sc.PATH_KEYS:  # as a dotted key, or inside a whole table
        for holder, key in ((out, f"{s}.{k}"), (out.get(s), k)):
            if isinstance(holder, dict) and key in holder:
                holder[key] = sc.absolute_path(holder[key], folder)
    return out


MAX_POINTS = 10_000  # most points enumerated unless --max-points says more


def load_sweep(path: str | Path, jobs: int | None = None, fatigue: bool | None = None,
               max_points: int = MAX_POINTS) -> Sweep:
    """Read and check a sweep file, enumerate its points (at most ``max_points``)."""
    path = Path(path)
    data = read_user_toml(path, "scenario", "sweep file")
    if not isinstance(data.get("sweep"), dict):
        raise ScenarioError("sweep", data.get("sweep"), "a [sweep] table (with base and grid)")
    sw = ConfigReader(data["sweep"], "sweep", SWEEP_KEYS)  # a typo: "did you mean"
    folder = path.resolve().parent
    name = sw.string("name", path.stem)
    check_name("sweep.name", name)
    if len(name) > 40:
        raise sw.error("name", name, "at most 40 characters")
    raw_base = sw.value("base")
    if raw_base is None:  # the sweep file is its own base scenario
        if not any(k != "sweep" for k in data):
            raise sw.error("base", None, "a base scenario file (or scenario sections in the "
                           "sweep file itself)")
        bases = [path.resolve()]
    else:
        items = raw_base if isinstance(raw_base, list) else [raw_base]
        if not items or not all(isinstance(b, str) and b for b in items):
            raise sw.error("base", raw_base, "a scenario file or a list of them")
        bases = []
        for b in items:
            p = folder / b  # as written (an absolute path stays): no ~ or $VARIABLE expansion
            if not p.is_file():
                raise InputFileError(str(p), "base scenario not found (sweep.base is "
                                     "relative to the sweep file)")
            bases.append(p.resolve())
    if jobs is None:
        jobs = sw.integer("jobs", max(1, (os.cpu_count() or 2) // 2), lo=1)
    elif isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise sw.error("jobs", jobs, "an integer >= 1")
    if fatigue is None:
        fatigue = sw.boolean("fatigue", False)
    channels = sw.value("channels", list(DEFAULT_CHANNELS))
    if not isinstance(channels, list) or not all(isinstance(c, str) for c in channels):
        raise sw.error("channels", channels, "a list of channel names")
    fixed = dict(sw.table("set"))
    for k, v in fixed.items():
        _check_override_key("sweep.set", k, v)
    grid = dict(sw.table("grid"))
    axes: list[Axis] = []
    design = None
    if sw.has("design"):
        design = parse_design(sw.value("design"), _check_override_key)
        for k in design.keys:
            if k in RESERVED or k in grid:
                raise ScenarioError(f"sweep.design.ranges.{k}", None, "a key that is neither "
                                    "a grid axis nor one of " + ", ".join(RESERVED))
    given_runs_dir = sw.optional_string("runs_dir")
    runs_dir = None if given_runs_dir is None else (folder / given_runs_dir).resolve()
    sw.value("description")  # free text
    from .fork import parse_fork_at

    fork_at = parse_fork_at(sw.value("fork_at"))
    if len(bases) > 1:
        axes.append(Axis("base", [b.stem for b in bases], [{} for _ in bases], bases))
    for key, spec in grid.items():
        where = f"sweep.grid.{key}"
        if key in RESERVED:
            raise ScenarioError(where, spec, "an axis name other than " + ", ".join(RESERVED))
        if isinstance(spec, list):
            if not spec:
                raise ScenarioError(where, spec, "a non-empty list of values")
            _check_override_key("sweep.grid", key, spec[0])
            axes.append(Axis(key, list(spec), [{key: v} for v in spec]))
        elif isinstance(spec, dict):
            if not spec:
                raise ScenarioError(where, spec, "a non-empty table of named variants")
            for vname, ov in spec.items():
                if not isinstance(ov, dict) or not ov:
                    raise ScenarioError(f"{where}.{vname}", ov,
                                        "a table of overrides, e.g. { \"run.h\" = 0.001 }")
                for k, v in ov.items():
                    _check_override_key(f"{where}.{vname}", k, v)
            axes.append(Axis(key, list(spec), list(spec.values())))
        else:
            raise ScenarioError(where, spec, "a list of values or a table of named variants")
    if design is not None:
        samples, sampled = design_axis(design)
        axes.append(Axis(AXIS, list(samples), sampled, params=sampled))
    n_points = math.prod(len(a.labels) for a in axes)
    if n_points > max_points:
        raise ScenarioError("sweep.grid", " x ".join(str(len(a.labels)) for a in axes) +
                            f" = {n_points} points", f"at most {max_points} points "
                            "(--max-points N to go past it)")
    sweep = Sweep(path=path, name=name, bases=bases, axes=axes, fixed=fixed, jobs=jobs,
                  fatigue=fatigue, channels=channels, raw_grid=grid, design=design,
                  runs_dir=runs_dir, fork_at=fork_at)
    seen: dict[str, int] = {}
    for index, combo in enumerate(itertools.product(*(range(len(a.labels)) for a in axes))):
        params: dict[str, Any] = {}
        overrides: dict[str, Any] = dict(fixed)
        base = bases[0]
        for axis, i in zip(axes, combo, strict=True):
            params[axis.name] = axis.labels[i]
            if axis.params is not None:
                params.update(axis.params[i])
            overrides.update(axis.overrides[i])
            if axis.bases is not None:
                base = axis.bases[i]
        pid = point_id(name, [params[a.name] for a in axes])
        if pid in seen:  # two values with the same slug (e.g. "a b" and "a_b")
            pid = point_id(name, [*(params[a.name] for a in axes), index])
        seen[pid] = index
        sweep.points.append(Point(index, pid, params, base, _absolute_paths(overrides, folder)))
    return sweep


def validate_points(sweep: Sweep, out: Path) -> None:
    """Preflight every point's scenario (n_steps, fingerprint, fork plan); SweepError."""
    from ..runner import resolve

    resolved_all: dict[str, dict[str, Any]] = {}
    for p in sweep.points:
        try:
            scenario = sc.load(p.base, p.fingerprint_args)
            p.fingerprint = fingerprint(scenario)
            resolved = resolve(copy.deepcopy(scenario), out / "runs" / p.id)
            p.n_steps = int(resolved["run"]["n_steps"])
        except SuscosimError as exc:
            raise SweepError(f"sweep point '{p.id}' ({_params_text(p.params)}): {exc}") from None
        resolved_all[p.id] = resolved
    if sweep.fork_at is not None:
        from .fork import plan_forks

        sweep.fork = plan_forks(sweep, out, resolved_all)


def fingerprint(doc: Any) -> str:
    return hashlib.sha256(json.dumps(doc, sort_keys=True, default=str).encode()).hexdigest()[:16]


def _params_text(params: dict[str, Any]) -> str:
    return ", ".join(f"{k}={v}" for k, v in params.items()) or "no parameters"


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
