"""Scenario files: one TOML file (e.g. scenarios/ch3_step_quarter_car.toml), validated before
anything starts.

The common sections are checked here, the model sections by the model factories of the nodes
that own them (at preflight). An error names the dotted key, the value and what was expected
(exit code 2). Every number of every section must be finite (:func:`check_finite`).
"""

from __future__ import annotations

import copy
import math
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from . import node_kinds
from .config import ConfigReader
from .errors import ScenarioError, UnknownKeyError
from .keys import check_name
from .safe_open import read_user_toml

SECTIONS = ("run", "vehicle", "tyre", "road", "controller", "fatigue", "sweep", "report",
            "nodes")


@dataclass(frozen=True)
class Key:
    """One key of a common section: its type, default and allowed values."""

    kind: type
    default: Any
    choices: tuple[Any, ...] | None = None
    positive: bool = False
    doc: str = ""
    low: float | None = None  # physical range (inclusive); positive: a strict 0
    high: float | None = None


RUN_KEYS: dict[str, Key] = {
    "name": Key(str, "run", doc="run name; the run id is <name>-<timestamp> unless run.id"),
    "id": Key(str, "", doc="explicit run id (letters, digits, _ . -)"),
    "t_end": Key(float, 0.0, doc="simulated time [s]; 0 = from road length / speed"),
    "h": Key(float, 0.001, positive=True, low=1e-6, high=0.1,
             doc="communication step [s], or \"auto\" (cosim/step_size.py)"),
    "h_min": Key(float, 1e-4, positive=True, low=1e-6, high=0.1,
                 doc="run.h = \"auto\": the smallest step [s]"),
    "h_max": Key(float, 4e-3, positive=True, low=1e-6, high=0.1,
                 doc="run.h = \"auto\": the largest step [s]"),
    "h_tol": Key(float, 1e-3, positive=True, low=1e-9, high=1.0,
                 doc="run.h = \"auto\": a step's energy residual over its bonds' energy"),
    "exchange": Key(str, "sequential", ("sequential", "parallel"),
                    doc="parallel: Jacobi, on the previous step's inputs (run_settings.py)"),
    "coupling": Key(str, "jacobian", ("hold", "linear", "jacobian"),
                    doc="the force inputs between two steps: zero-order hold (the thesis), "
                        "linear extrapolation, or linearised with the sent dF/dz, dF/dv"),
    "substeps": Key(int, 4, positive=True, high=10000,
                    doc="plant integration substeps per step"),
    "coupling_h": Key(float, 0.0, low=0.0, high=0.1,
                      doc="multi-rate: the exchange's step [s], a whole multiple of run.h "
                          "(the plant's); 0 = run.h"),
    "sink_window_s": Key(float, 10.0, low=0.0, high=1e6,
                         doc="how far (simulated s) a sink may lag behind; 0 = unbounded"),
    "mode": Key(str, "distributed", ("distributed", "monolithic", "reference"),
                doc="monolithic: run.transport = \"inprocess\"; reference: SciPy solve_ivp "
                    "of the lumped model"),
    "transport": Key(str, "zenoh", ("zenoh", "inprocess"),
                     doc="inprocess: the node models stepped in one process, no bus "
                         "(bit-identical tables)"),
    "stall_timeout_s": Key(float, 5.0, positive=True, high=3600.0,
                           doc="a node that makes no progress this long ends the run [s]"),
    "start_timeout_s": Key(float, 60.0, positive=True, high=3600.0,
                           doc="how long to wait for every node to be ready [s]"),
    "checkpoint_every_s": Key(float, 0.0, low=0.0, high=1e6,
                              doc="checkpoint period (simulated s) for --resume / --fork; "
                                  "0 = never"),
    "checkpoint_keep": Key(int, 2, low=0, high=1_000_000,
                           doc="newest complete checkpoints kept; 0 = every one"),
    "rtol": Key(float, 1e-10, positive=True, low=1e-14, high=1e-2,
                doc="reference mode: solve_ivp relative tolerance"),
}


RESOLVED_RUN_KEYS = ("dir", "n_steps", "nodes", "t_end_source", "resume", "adaptive")
"""Keys the orchestrator adds when it resolves a scenario."""


def _read_key(r: ConfigReader, name: str, spec: Key) -> Any:
    if spec.choices is not None:
        return r.choice(name, spec.choices, spec.default)
    if spec.kind is float:
        lo = spec.low if spec.low is not None else 0.0 if spec.positive else None
        return r.number(name, spec.default, lo=lo, hi=spec.high,
                        lo_open=spec.positive and spec.low is None)
    if spec.kind is int:
        ilo = int(spec.low) if spec.low is not None else 1 if spec.positive else None
        return r.integer(name, spec.default, lo=ilo,
                         hi=int(spec.high) if spec.high is not None else None)
    if spec.kind is bool:
        return r.boolean(name, spec.default)
    return r.string(name, spec.default, empty=True)


PHYSICAL_RANGES: tuple[tuple[str, str, float, float, str], ...] = (
    ("vehicle", "*mass*", 1e-3, 1e5, "kg"),
    ("vehicle", "*inertia*", 1e-3, 1e6, "kg m^2"),
    ("vehicle", "*stiffness*", 0.0, 1e9, "N/m (N m/deg for a torsion bar)"),
    ("vehicle", "track", 0.1, 10.0, "m"),
    ("vehicle", "wheelbase", 0.1, 20.0, "m"),
    ("tyre", "stiffness", 1.0, 1e9, "N/m"),
    ("tyre", "contact_length", 1e-4, 2.0, "m"),
    ("controller", "c", 0.0, 1e7, "N s/m"),
    ("controller", "c_*", 0.0, 1e7, "N s/m"),
    ("controller", "I_*", 0.0, 100.0, "A"),
    ("road", "height", -1.0, 1.0, "m"),
    ("road", "depth", -1.0, 1.0, "m"),
    ("road", "speed_kmh", 0.0, 500.0, "km/h"),
    ("road", "length_m", 0.0, 1e7, "m"),
)
"""(section, key pattern, lowest, highest, unit): the physical range of the numbers of the
model sections, at any depth (``road.events[2].height``); outside is a ScenarioError. The
models check more; this catches what no model would run sensibly (a 1e30 kg body)."""


def check_ranges(scenario: dict[str, Any]) -> None:
    from fnmatch import fnmatchcase

    def walk(section: str, value: Any, key: str) -> None:
        if isinstance(value, dict):
            for k, v in value.items():
                walk(section, v, f"{key}.{k}")
        elif isinstance(value, list):
            for i, v in enumerate(value):
                walk(section, v, f"{key}[{i}]")
        elif type(value) in (int, float):
            leaf = key.rsplit(".", 1)[-1].split("[", 1)[0]
            for sec, pattern, lo, hi, unit in PHYSICAL_RANGES:
                if sec == section and fnmatchcase(leaf, pattern) and not lo <= value <= hi:
                    raise ScenarioError(key, value, f"a number in {lo:g}..{hi:g} {unit}")

    for section in ("vehicle", "tyre", "road", "controller"):
        if isinstance(scenario.get(section), dict):
            walk(section, scenario[section], section)


def check_finite(value: Any, key: str = "") -> None:
    """Refuse a non-finite number anywhere in a scenario, naming its dotted key."""
    if isinstance(value, float) and not math.isfinite(value):
        raise ScenarioError(key, value, "a finite number")
    if isinstance(value, dict):
        for k, v in value.items():
            check_finite(v, f"{key}.{k}" if key else str(k))
    elif isinstance(value, list | tuple):
        for i, v in enumerate(value):
            check_finite(v, f"{key}[{i}]")


def validate_common(scenario: dict[str, Any]) -> dict[str, Any]:
    """A copy of ``scenario``, sections, numbers and ``run`` checked, defaults filled."""
    out = copy.deepcopy(scenario)
    check_finite(out)
    check_ranges(out)
    for name, value in out.items():
        if name not in SECTIONS:
            raise ScenarioError(name, "(section)", "one of the sections " + ", ".join(SECTIONS))
        if not isinstance(value, dict):
            raise ScenarioError(name, value, "a table")
    run = out.setdefault("run", {})
    r = ConfigReader(run, "run")
    r.only(RUN_KEYS, unlisted=RESOLVED_RUN_KEYS)
    if run.get("h") == "auto" or run.get("adaptive"):  # the step is chosen as the run goes
        run["adaptive"] = True
        run["h"] = _read_key(r, "h_min", RUN_KEYS["h_min"])  # the finest grid: N's bound
    for key, spec in RUN_KEYS.items():
        run[key] = _read_key(r, key, spec)
    if run.get("adaptive"):
        run["h"] = run["h_min"]
        if not run["h_min"] < run["h_max"]:
            raise ScenarioError("run.h_max", run["h_max"], f"more than run.h_min = "
                                f"{run['h_min']:g} s (run.h = \"auto\")")
    if run["mode"] == "monolithic" or run["transport"] == "inprocess":
        if run["mode"] != "reference":  # one engine, two names (docs/cosim.md)
            run["mode"], run["transport"] = "monolithic", "inprocess"
    _coupling_step(run)
    if run["id"]:
        check_name("run.id", run["id"])
    check_name("run.name", run["name"])
    if run["t_end"] < 0:
        raise ScenarioError("run.t_end", run["t_end"], "a duration >= 0 s")
    for section in ("vehicle", "tyre", "road", "controller"):
        out.setdefault(section, {})
    return out


def _coupling_step(run: dict[str, Any]) -> None:
    """Resolve ``run.coupling_h`` (multi-rate, DESIGN.md) in place: run.h becomes the
    coupling step, run.substeps x coupling_h / h the plant's substeps in it (idempotent)."""
    every = run["coupling_h"]
    if not every:
        return
    if run.get("adaptive"):
        raise ScenarioError("run.coupling_h", every, "0 with run.h = \"auto\"")
    h = run["h"]
    m = round(every / h)
    if m < 1 or abs(m * h - every) > 1e-9 * every:
        raise ScenarioError("run.coupling_h", every, f"a whole multiple of run.h = {h:g} s")
    run["h"], run["substeps"], run["coupling_h"] = every, run["substeps"] * m, every


MAX_STEPS = 100_000_000
"""Most communication steps a run may have (14 h at 2000 steps/s; a journal of ~50 GB)."""


def n_steps(t_end: float, h: float) -> int:
    """Number of communication steps N so that t_N = t_end (k = 0..N)."""
    ratio = t_end / h
    if not math.isfinite(ratio) or ratio > MAX_STEPS:
        raise ScenarioError("run.t_end", t_end, f"at most {MAX_STEPS} steps of h = {h} s "
                            f"(got {ratio:.3g})")
    n = int(round(ratio))
    if n < 1:
        raise ScenarioError("run.t_end", t_end, f"at least one step of h = {h} s")
    return n


def parse_value(text: str) -> Any:
    """A ``--set`` value in TOML syntax (``0.002``, ``true``, ``"tss1"``), else a plain string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def apply_override(scenario: dict[str, Any], assignment: str) -> None:
    """Apply one ``KEY=VALUE`` (dotted key) in place."""
    if "=" not in assignment:
        raise ScenarioError(assignment, None, "KEY=VALUE, e.g. run.h=0.002")
    dotted, text = assignment.split("=", 1)
    parts = dotted.strip().split(".")
    value = parse_value(text.strip())
    if not all(parts) or (len(parts) < 2 and not isinstance(value, dict)):
        raise ScenarioError(dotted, text, "a dotted key section.key, e.g. run.h (or a whole "
                            "section as a table, e.g. 'controller={law=\"tss1\"}')")
    node = scenario
    for part in parts[:-1]:
        node = node.setdefault(part, {})
        if not isinstance(node, dict):
            raise ScenarioError(dotted, text, f"'{part}' to be a table")
    node[parts[-1]] = value  # a table replaces the whole table at that key


def _override_key(assignment: str) -> str:  # the KEY of KEY=VALUE
    return assignment.split("=", 1)[0].strip()


def override_hint(exc: ScenarioError, overrides: list[str] | tuple[str, ...]) -> ScenarioError:
    """``exc`` with a hint when ``--set`` changed single keys of a table that now has an
    unknown key left over from the file (``controller.law`` set, ``controller.c`` kept): how
    to give the table whole instead."""
    if not isinstance(exc, UnknownKeyError):
        return exc
    table, _, leaf = exc.key.rpartition(".")
    if not table:
        return exc
    set_keys = [_override_key(a) for a in overrides]
    if exc.key in set_keys:
        return exc  # the user typed that key: a typo, the message already says so
    mine = [a for a in overrides if _override_key(a).rpartition(".")[0] == table]
    if not mine:
        return exc
    whole = ", ".join(f"{_override_key(a).rpartition('.')[2]}={a.split('=', 1)[1].strip()}"
                      for a in mine)
    return exc.with_hint(
        f"'{leaf}' comes from the scenario file: --set {_override_key(mine[0])}=... changes "
        f"one key of [{table}] and keeps the others; to replace the whole table, give it "
        f"whole: --set '{table}={{{whole}, ...}}' with the keys it takes")


_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _toml_key(key: str) -> str:
    import json

    return key if _BARE_KEY.fullmatch(key) else json.dumps(key)


def _toml_value(value: Any) -> str:
    """One TOML value: floats with their exact ``repr``, tables inline."""
    import json

    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float | str):
        return json.dumps(value) if isinstance(value, str) else repr(value)
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_toml_key(str(k))} = {_toml_value(v)}"
                               for k, v in value.items()) + "}"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"no TOML form for {type(value).__name__}")


def to_toml(scenario: dict[str, Any]) -> str:
    """A scenario as TOML text that :func:`tomllib.loads` reads back equal (``check`` prints
    a resolved scenario with it): one ``[section]`` per table, its sub-tables inline."""
    lines: list[str] = []
    for name, section in scenario.items():
        if not isinstance(section, dict):
            lines.append(f"{_toml_key(name)} = {_toml_value(section)}")
            continue
        lines.append(f"[{_toml_key(name)}]")
        lines += [f"{_toml_key(str(k))} = {_toml_value(v)}" for k, v in section.items()]
        lines.append("")
    return "\n".join(lines)


def load(path: str | Path, overrides: list[str] | tuple[str, ...] = ()) -> dict[str, Any]:
    """Read a scenario TOML file, apply ``--set`` overrides, validate the common sections."""
    path = Path(path)
    scenario = read_user_toml(path, "scenario", "scenario file")
    absolute_paths(scenario, path.resolve().parent)
    for assignment in overrides:
        apply_override(scenario, assignment)
    absolute_paths(scenario, Path.cwd())  # paths given with --set: relative to where typed
    return validate_common(scenario)


PATH_KEYS = node_kinds.path_keys()  # (section, key) of file paths: relative to the file


def absolute_path(value: Any, folder: Path) -> Any:
    """``value`` (a string or a list of them) with relative file paths made absolute against
    ``folder``; ``"builtin..."`` and, in a list, bare names without a suffix are left."""
    if isinstance(value, list):
        return [absolute_path(v, folder) if isinstance(v, str) and Path(v).suffix else v
                for v in value]
    if not isinstance(value, str) or not value or value.startswith("builtin"):
        return value
    p = Path(value)  # as written: no ~ or $VARIABLE expansion
    return value if p.is_absolute() else str(folder / p)


def absolute_paths(scenario: dict[str, Any], folder: Path) -> None:
    """Make the relative file paths of ``scenario`` absolute against ``folder``, in place."""
    for section, key in PATH_KEYS:
        sec = scenario.get(section)
        if isinstance(sec, dict) and key in sec:
            sec[key] = absolute_path(sec[key], folder)
