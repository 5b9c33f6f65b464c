"""Fatigue of a finished run folder (table + resolved scenario in, CSV/JSON/PNG out), or of a
measured load file (RPC III, MDF 4, CSV, Parquet) mapped to the arm's load channels."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from cosim.errors import InputFileError, ScenarioError

from .config import FatigueConfig
from .damage_map import plot_damage_map
from .influence import short_channel
from .worker import FatigueResult, analyse, load_influence


def read_table(run_dir: Path) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """(t, {column: values}) from ``table.parquet`` or else ``table.csv`` (only load columns
    ``plant/arm/...`` are kept; :func:`cosim.table.read_table` reads them)."""
    from cosim.table import read_table as read_run_table

    src = next((p for p in (run_dir / "table.parquet", run_dir / "table.csv") if p.is_file()),
               None)
    if src is None:
        raise InputFileError(str(run_dir), "no table.parquet or table.csv in the run folder")
    cols = {n: np.asarray(v, dtype=float)
            for n, v in read_run_table(src, keep=lambda n: n.startswith("plant/arm/")).items()}
    cols.pop("k", None)
    if "t" not in cols:
        raise InputFileError(str(src), "no column 't'", 1 if src.suffix == ".csv" else None)
    t = cols.pop("t")
    if t.size < 2:
        raise InputFileError(str(src), "fewer than 2 samples")
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise InputFileError(str(src), "column 't' is not strictly increasing")
    return t, cols


def track_length(scenario: dict, t: np.ndarray) -> float:
    """road.length_m, else road.speed_kmh / 3.6 x run.t_end (else x the table's duration)."""
    road = scenario.get("road", {}) or {}
    if "length_m" in road:
        v = road["length_m"]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or v <= 0:
            raise ScenarioError("road.length_m", v, "a length > 0 (m)")
        return float(v)
    speed = road.get("speed_kmh")
    if speed is None:
        raise ScenarioError("road.speed_kmh", None,
                            "a speed (km/h), or road.length_m / fatigue.track_length_m")
    if isinstance(speed, bool) or not isinstance(speed, (int, float)) or speed <= 0:
        raise ScenarioError("road.speed_kmh", speed, "a speed > 0 (km/h)")
    t_end = (scenario.get("run", {}) or {}).get("t_end")
    if t_end is None:
        t_end = float(t[-1] - t[0])
    return float(speed) / 3.6 * float(t_end)


def _merge(base: dict, overrides: dict) -> dict:
    out = dict(base)
    for k, v in overrides.items():
        if "." in k:
            head, rest = k.split(".", 1)
            sub = out.get(head, {})
            out[head] = _merge(sub if isinstance(sub, dict) else {}, {rest: v})
        elif isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = _merge(out[k], v)
        else:
            out[k] = v
    return out


def write_results(result: FatigueResult, out: Path) -> None:
    """damage_per_node.csv, summary.json, damage_map.png in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    life = result.life_repeats_per_node()
    with open(out / "damage_per_node.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["node_id", "x_m", "y_m", "z_m", "damage_per_pass", "life_repeats",
                    "life_km", "eq_range_max_pa", "eq_max_pa", "eq_min_pa", "cycles"])
        xyz = result.node_xyz if result.node_xyz is not None else \
            np.full((result.damage.size, 3), np.nan)
        for i in range(result.damage.size):
            w.writerow([int(result.node_ids[i]), *(f"{v:.6g}" for v in xyz[i]),
                        f"{result.damage[i]:.6e}", f"{life[i]:.6e}",
                        f"{life[i] * result.track_length_m / 1000:.6e}",
                        f"{result.eq_range_max[i]:.6e}", f"{result.eq_max[i]:.6e}",
                        f"{result.eq_min[i]:.6e}", f"{result.n_cycles[i]:g}"])
    (out / "summary.json").write_text(result.to_json())
    plot_damage_map(result, out / "damage_map.png")


def _scenario_json(sc_path: Path) -> dict:
    try:
        scenario = json.loads(sc_path.read_text())
    except json.JSONDecodeError as exc:
        raise InputFileError(str(sc_path), f"invalid JSON ({exc.msg})", exc.lineno) from None
    except OSError as exc:
        raise InputFileError(str(sc_path), f"cannot read: {exc.strerror}") from None
    if not isinstance(scenario, dict):
        raise InputFileError(str(sc_path), "top level is not an object")
    return scenario


def settings_source(source: Path | None) -> tuple[dict, Path]:
    """(scenario, base folder) that a load file's fatigue settings come from: a run folder
    (its ``scenario.json``), a scenario TOML, or nothing (``{}``: the defaults)."""
    if source is None:
        return {}, Path.cwd()
    source = Path(source)
    if source.is_dir():
        sc_path = source / "scenario.json"
        if not sc_path.is_file():
            raise InputFileError(str(sc_path), "resolved scenario not found")
        return _scenario_json(sc_path), source
    if not source.is_file():
        raise InputFileError(str(source), "scenario or run folder not found")
    if source.suffix.lower() == ".json":
        return _scenario_json(source), source.parent
    from cosim import scenario as sc

    return sc.load(source), source.parent


def fatigue_load_file(path: Path, overrides: dict | None = None,
                      settings: Path | None = None, mapping: dict | None = None,
                      out: Path | None = None) -> FatigueResult:
    """Fatigue of the arm under a load file (RPC III / MDF 4 / CSV / Parquet).

    The fatigue section (and the road's length, for life in km) come from ``settings`` (a run
    folder or a scenario, see :func:`settings_source`) with ``overrides`` merged in; the track
    length is ``track_length_m`` if given, else the scenario's road. The file's channels are
    mapped to the arm's load channels by :func:`load_file.arm_loads` (``mapping`` from
    :func:`load_file.parse_map`). Results go to ``out`` (default ``<file>.fatigue/`` beside
    the file), written as for a run.
    """
    from cosim.formats import read_channels

    from .load_file import arm_loads

    path = Path(path)
    scenario, base = settings_source(settings)
    section = scenario.get("fatigue", {}) or {}
    if not isinstance(section, dict):
        raise ScenarioError("fatigue", section, "a table")
    cfg = FatigueConfig.from_dict(_merge(section, overrides or {}), "fatigue", base_dir=base)
    cs = read_channels(path)
    loads = arm_loads(cs, str(path), load_influence(cfg).case_names, mapping)
    if cfg.track_length_m is not None:
        L = cfg.track_length_m
    elif scenario.get("road"):
        L = track_length(scenario, cs.t)
    else:
        raise ScenarioError("fatigue.track_length_m", None,
                            f"the length of road {path.name} covers (m): --set "
                            "track_length_m=... or --scenario RUN_DIR|SCENARIO.toml")
    result = analyse(cs.t, loads, cfg, L)
    result.source = f"file:{path.name}"
    write_results(result, Path(out) if out is not None else
                  path.with_name(path.name + ".fatigue"))
    return result


def fatigue_run_dir(run_dir: Path, overrides: dict | None = None) -> FatigueResult:
    """Run the fatigue worker on a finished run folder and write ``run_dir/fatigue/``.

    Reads ``table.parquet`` (or ``table.csv``) and ``scenario.json`` (its ``fatigue``
    section, with ``overrides`` merged in: dotted keys relative to that section).
    """
    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise InputFileError(str(run_dir), "run folder not found")
    sc_path = run_dir / "scenario.json"
    if not sc_path.is_file():
        raise InputFileError(str(sc_path), "resolved scenario not found")
    try:
        scenario = json.loads(sc_path.read_text())
    except json.JSONDecodeError as exc:
        raise InputFileError(str(sc_path), f"invalid JSON ({exc.msg})", exc.lineno) from None
    if not isinstance(scenario, dict):
        raise InputFileError(str(sc_path), "top level is not an object")
    section = scenario.get("fatigue", {}) or {}
    if not isinstance(section, dict):
        raise ScenarioError("fatigue", section, "a table")
    section = _merge(section, overrides or {})
    cfg = FatigueConfig.from_dict(section, "fatigue", base_dir=run_dir)
    t, loads = read_table(run_dir)
    if not any(short_channel(k) for k in loads):
        raise InputFileError(str(run_dir / "table"), "no plant/arm/... load columns")
    L = cfg.track_length_m if cfg.track_length_m is not None else track_length(scenario, t)
    result = analyse(t, loads, cfg, L)
    write_results(result, run_dir / "fatigue")
    return result
