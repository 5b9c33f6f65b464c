"""Fatigue of a finished run folder (table + resolved scenario in, CSV/JSON/PNG out), or of a
measured load file (RPC III, MDF 4, CSV, Parquet) mapped to the arm's load channels."""

from __future__ import annotations

import csv
import hashlib
import json
import math
import os
import shutil
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from cosim.errors import InputFileError, ScenarioError
from cosim.safe_open import read_user_text

from .config import FatigueConfig
from .critical_plane_run import with_critical_planes
from .lib.damage import SPECTRAL_METHODS
from .lib.influence_set import short_channel
from .map_render import plot_damage_map
from .more_parts import load_channel, more_parts, part_channels, primary_name
from .run_stream import Batches, Scan
from .worker import FatigueResult, load_influence


def read_table(run_dir: Path) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """(t, {column: values}) of the ``plant/arm/...`` load columns of ``table.parquet`` or
    else ``table.csv`` (:func:`.run_stream.table_batches`), whole."""
    from .run_stream import table_batches, table_source

    src = table_source(run_dir)
    got = list(table_batches(src)())
    t = np.concatenate([b[0] for b in got]) if got else np.zeros(0)
    cols = {c: np.concatenate([b[1][c] for b in got]) for c in (got[0][1] if got else {})}
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


def strict_json(obj):
    """``obj`` made strict JSON: inf -> "inf", -inf -> "-inf", NaN -> None, NumPy scalars and
    arrays -> Python numbers and lists (``json.dumps(..., allow_nan=False)`` then holds)."""
    if isinstance(obj, dict):
        return {str(k): strict_json(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [strict_json(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return strict_json(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        if math.isnan(v):
            return None
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return v
    return obj


def summary_dict(result: FatigueResult, extra: dict | None = None) -> dict:
    """What ``summary.json`` holds: the result's summary, ``fails_first_cycle`` (a node whose
    damage per pass is infinite: life 0, not an error), and ``extra`` merged in."""
    s = result.summary()
    fails = bool(np.isinf(np.asarray(result.damage, dtype=float)).any())
    s["fails_first_cycle"] = fails
    if fails:
        s["min_life_km"] = 0.0
        s["min_life_repeats"] = 0.0
        s["verdict"] = ("fails on the first cycle: a cycle's stress (mean-stress corrected) "
                        "is at or beyond the strength; life 0 km")
    s.update(extra or {})
    if result.config.get("critical_plane") and "critical_plane" not in s:
        s["critical_plane"] = {"method": result.config["critical_plane"], "computed": False,
                               "note": "not computed live: the lives are the "
                                       f"{result.config['equivalent']} pass's; suscosim "
                                       "fatigue RUN_DIR computes the critical planes"}
    return strict_json(s)


def _write_csv(result: FatigueResult, path: Path) -> None:
    life = result.life_repeats_per_node()
    with open(path, "w", newline="") as fh:
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


def replace_folder(tmp: Path, out: Path) -> None:
    """Put the finished folder ``tmp`` at ``out``: the old ``out`` (if any) is renamed aside
    first and removed after, so ``out`` is always one whole result, never a mix."""
    old = out.with_name(f".{out.name}.old-{os.getpid()}")
    if out.exists():
        if old.exists():
            shutil.rmtree(old)
        os.replace(out, old)
    os.replace(tmp, out)
    if old.exists():
        shutil.rmtree(old, ignore_errors=True)


def write_results(result: FatigueResult, out: Path, extra: dict | None = None,
                  extra_files: Callable[[Path], None] | None = None) -> None:
    """damage_per_node.csv, summary.json (strict JSON, `summary_dict`), damage_map.png in
    ``out``, written into a folder beside it and renamed into place (`replace_folder`).

    ``extra``: more summary keys; ``extra_files(folder)``: writes more files into the new
    folder before it is renamed (the batch outputs of :mod:`outputs`).
    """
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.new-", dir=out.parent))
    try:
        tmp.chmod(0o755)  # mkdtemp makes it 0700; a results folder is as readable as others
        fill_folder(result, tmp, extra, extra_files)
        replace_folder(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def fill_folder(result: FatigueResult, folder: Path, extra: dict | None = None,
                extra_files: Callable[[Path], None] | None = None) -> None:
    """The files of :func:`write_results` written into an existing ``folder`` (no rename:
    a part's folder inside the primary's new folder, renamed into place with it)."""
    _write_csv(result, folder / "damage_per_node.csv")
    if extra_files is not None:
        extra_files(folder)
    text = json.dumps(summary_dict(result, extra), indent=2, allow_nan=False)
    (folder / "summary.json").write_text(text)
    plot_damage_map(result, folder / "damage_map.png")


def part_entry(name: str, folder: str, channel: str, result: FatigueResult,
               source: str | None, methods: dict | None = None) -> dict:
    """A part's line in the primary summary's ``parts`` (a run with ``[fatigue] parts``)."""
    rng = (methods or {}).get("life_range_km")
    return {"name": name, "folder": folder, "part_file": source,
            "load_channel": f"plant/{channel}", "min_life_km": result.life_km,
            "min_life_repeats": result.life_repeats, "max_damage_per_pass": result.max_damage,
            "critical_node_id": result.critical_node_id, "life_range_km": rng}


def parts_summary(cfg: FatigueConfig, result: FatigueResult, methods: dict | None,
                  entries: list[dict]) -> list[dict]:
    """The primary summary's ``parts``: the primary part's entry, then the more parts'."""
    return [part_entry(primary_name(cfg), ".", load_channel(cfg), result,
                       None if cfg.influence.startswith("builtin") else cfg.influence, methods),
            *entries]


def with_parts(files: Callable[[Path], None] | None,
               parts: Sequence[tuple[str, FatigueResult, dict, Callable[[Path], None] | None]]
               ) -> Callable[[Path], None] | None:
    """``files`` and then each more part's folder (``<name>/``, :func:`fill_folder`)."""
    if not parts:
        return files

    def write(folder: Path) -> None:
        if files is not None:
            files(folder)
        for name, res, extra, more in parts:
            sub = folder / name
            sub.mkdir()
            sub.chmod(0o755)
            fill_folder(res, sub, extra, more)
    return write


def settings_hash(overrides: dict) -> str:
    """8 hex digits of the SHA-256 of the what-if settings (sorted JSON)."""
    text = json.dumps(strict_json(overrides), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:8]


def _scenario_json(sc_path: Path) -> dict:
    try:
        scenario = json.loads(read_user_text(sc_path, "scenario", "the run's scenario.json",
                                             inside=sc_path.parent))
    except json.JSONDecodeError as exc:
        raise InputFileError(str(sc_path), f"invalid JSON ({exc.msg})", exc.lineno) from None
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


def _config(scenario: dict, overrides: dict | None, base: Path) -> FatigueConfig:
    """The scenario's ``[fatigue]`` with ``overrides`` (dotted keys relative to it) merged in."""
    section = scenario.get("fatigue", {}) or {}
    if not isinstance(section, dict):
        raise ScenarioError("fatigue", section, "a table")
    return FatigueConfig.from_dict(_merge(section, overrides or {}), "fatigue", base_dir=base)


def _extra(peaks: dict[str, float], cfg: FatigueConfig, what_if: dict | None) -> dict:
    """The summary keys of a batch analysis: ``unmapped_channels``, the load channels no
    influence case answers to (their load is not in the stresses) with their peak |load| (N
    or N m), and ``what_if`` (the settings and their :func:`settings_hash`)."""
    cases = list(load_influence(cfg).case_names)
    extra: dict = {"unmapped_channels": [{"channel": c, "peak_abs": p} for c, p in peaks.items()
                                         if short_channel(c) not in cases]}
    if what_if:
        extra["what_if"] = {"settings": what_if, "hash": settings_hash(what_if)}
    return extra


def _spectral_and_write(t: np.ndarray, loads: dict[str, np.ndarray], cfg: FatigueConfig,
                        L: float, out: Path, source: str, what_if: dict | None,
                        progress: Callable[[str], None] | None) -> FatigueResult:
    """A spectral method (:mod:`.spectral_life`: the PSD of the whole history, no rainflow
    outputs): check the loads, analyse, write ``out`` whole."""
    from .load_file import check_loads
    from .spectral_life import spectral_analyse

    check_loads(loads, t, source)
    (progress or (lambda _msg: None))(f"fatigue: {len(t)} samples x {len(loads)} channels, "
                                      "primary S-N curve")
    result, more = spectral_analyse(t, loads, cfg, L)
    peaks = {c: float(np.max(np.abs(v))) if np.size(v) else 0.0 for c, v in loads.items()}
    write_results(result, out, {**_extra(peaks, cfg, what_if), **more})
    return result


def fatigue_load_file(path: Path, overrides: dict | None = None,
                      settings: Path | None = None, mapping: dict | None = None,
                      out: Path | None = None,
                      progress: Callable[[str], None] | None = None) -> FatigueResult:
    """Fatigue of the arm under a load file (RPC III / MDF 4 / CSV / Parquet).

    The fatigue section (and the road's length, for life in km) come from ``settings`` (a run
    folder or a scenario, see :func:`settings_source`) with ``overrides`` merged in; the track
    length is ``track_length_m`` if given, else the scenario's road. The file's channels are
    mapped to the arm's load channels by :func:`load_file.arm_loads` (``mapping`` from
    :func:`load_file.parse_map`), checked by :func:`load_file.check_loads`. Results go to
    ``out`` (default ``<file>.fatigue/`` beside the file), written as for a run.
    """
    from cosim.formats import read_channels

    from .load_file import arm_loads

    path = Path(path)
    scenario, base = settings_source(settings)
    cfg = _config(scenario, overrides, base)
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
    out = Path(out) if out is not None else path.with_name(path.name + ".fatigue")
    t = np.asarray(cs.t, dtype=float)
    if cfg.method in SPECTRAL_METHODS:
        result = _spectral_and_write(t, loads, cfg, L, out, str(path), None, progress)
    else:
        result, extra, files, _m = _stream(lambda: iter([(t, loads)]), str(path), str(path),
                                           cfg, lambda _s: L, None, progress)
        write_results(result, out, extra, files)
    result.source = f"file:{path.name}"
    return result


def _stream(batches: Batches, src: str, source: str, cfg: FatigueConfig,
            length: Callable[[Scan], float], what_if: dict | None,
            progress: Callable[[str], None] | None
            ) -> tuple[FatigueResult, dict, Callable[[Path], None], dict | None]:
    """One part's batch analysis of a load history in row batches (:mod:`.run_stream`; the
    table file ``src``, the loads named as ``source``; ``length``: the track length (m) from
    the scan): (result, summary keys, writer of its batch files, its ``sn_methods``)."""
    from . import run_stream as rs

    say = progress or (lambda _msg: None)
    s = rs.scan(batches, src, cfg.residue, source)
    if not s.channels:
        raise InputFileError(source, f"no plant/{load_channel(cfg)}/... load columns")
    result, methods, matrices = rs.analyse_streamed(batches, cfg, length(s), s, say)
    extra = _extra({c: ch.peak_abs for c, ch in s.channels.items()}, cfg, what_if)
    files, more = rs.outputs_streamed(batches, cfg, s, result, methods, matrices, say)
    extra.update(more)
    files = with_critical_planes((b for _t, b in batches()), cfg, result, extra, files, say)
    return result, extra, files, methods


def _stream_and_write(run_dir: Path, scenario: dict, cfg: FatigueConfig, out: Path,
                      what_if: dict | None, progress: Callable[[str], None] | None
                      ) -> FatigueResult:
    """A run's table read in row batches (:mod:`.run_stream`: memory that does not grow
    with the run), analysed by the live node's block engine, the batch outputs computed as the
    batches pass, ``out`` written whole; with ``[fatigue] parts`` each more part the same way,
    into ``out/<name>/``, and the primary summary's ``parts`` naming them all."""
    from .run_stream import table_batches, table_source

    src = table_source(run_dir)

    def one(c: FatigueConfig, channel: str
            ) -> tuple[FatigueResult, dict, Callable[[Path], None], dict | None]:
        def length(s: Scan) -> float:
            return c.track_length_m if c.track_length_m is not None else \
                track_length(scenario, np.array([s.t0, s.t_last]))
        return _stream(table_batches(src, channel=channel, cases=part_channels(c)), str(src),
                       str(run_dir / "table"), c, length, what_if, progress)

    result, extra, files, methods = one(cfg, load_channel(cfg))
    parts = []
    entries = []
    for mp in more_parts(cfg):
        (progress or (lambda _msg: None))(f"fatigue: part {mp.name} (plant/{mp.channel})")
        r, e, f, m = one(mp.cfg, mp.channel)
        parts.append((mp.name, r, e, f))
        entries.append(part_entry(mp.name, mp.name, mp.channel, r, mp.cfg.influence, m))
    if parts:
        extra["parts"] = parts_summary(cfg, result, methods, entries)
    write_results(result, out, extra, with_parts(files, parts))
    return result


def results_folder(run_dir: Path, overrides: dict | None, out: Path | None = None) -> Path:
    """Where batch results of a run go: ``out`` if given; else ``run_dir/fatigue`` without
    overrides (the live results' place) or ``run_dir/fatigue-<settings_hash>`` for a what-if
    (any override: the live ``fatigue/`` stays)."""
    if out is not None:
        return Path(out)
    return Path(run_dir) / ("fatigue" if not overrides
                            else f"fatigue-{settings_hash(overrides)}")


def fatigue_run_dir(run_dir: Path, overrides: dict | None = None, out: Path | None = None,
                    progress: Callable[[str], None] | None = None) -> FatigueResult:
    """Run the fatigue worker on a finished run folder and write its results folder
    (`results_folder`: ``fatigue/``, ``fatigue-<hash>/`` for a what-if, or ``out``).

    Reads ``table.parquet`` (or ``table.csv``) and ``scenario.json`` (its ``fatigue``
    section, with ``overrides`` merged in: dotted keys relative to that section). A what-if's
    settings are in its ``summary.json`` (``what_if``); overrides that leave the run's own
    settings as they are (``--set mesh_size_m=0.03`` on a run made with it) are not a
    what-if: they rewrite ``fatigue/``.
    """
    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise InputFileError(str(run_dir), "run folder not found")
    scenario, _ = settings_source(run_dir)
    cfg = _config(scenario, overrides, run_dir)
    if overrides and cfg == _config(scenario, None, run_dir):
        overrides = {}  # settings that only repeat the run's own: not a what-if
    folder = results_folder(run_dir, overrides, out)
    if cfg.method in SPECTRAL_METHODS:  # the whole table at once: its PSD needs it
        if cfg.parts:
            raise ScenarioError("fatigue.parts", list(cfg.parts), f"none with method "
                                f"{cfg.method!r} (the lower arm only; method = \"stress_life\""
                                " assesses the parts)")
        t, loads = read_table(run_dir)
        L = cfg.track_length_m if cfg.track_length_m is not None else \
            track_length(scenario, t)
        result = _spectral_and_write(t, loads, cfg, L, folder, str(run_dir / "table"),
                                     overrides or None, progress)
    else:
        result = _stream_and_write(run_dir, scenario, cfg, folder, overrides or None, progress)
    result.results_dir = folder  # type: ignore[attr-defined]  # where it went, for the CLI
    return result
