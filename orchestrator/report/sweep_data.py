"""The sweep as the report reads it from its folder (sweep.json, runs/<id>/, results): points,
grid axes, the law axis, changes against passive. Files only, no :mod:`orchestrator.sweep`."""

from __future__ import annotations

import csv
import json
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cosim.errors import SuscosimError
from cosim.safe_open import open_user_text, read_user_text

from .markup import fmt, is_num
from .run_data import BadInput, RunData, is_run_dir, load_run
from .signals import first_present

LAW_KEY = "controller.law"
PASSIVE = "passive"


@dataclass
class Point:
    id: str
    params: dict[str, Any]
    run_dir: Path
    run: RunData | None
    overrides: dict[str, Any] = field(default_factory=dict)

    @property
    def law(self) -> str | None:
        """A ``controller.law`` parameter, else the point's overrides, else its scenario's."""
        if LAW_KEY in self.params:
            return str(self.params[LAW_KEY])
        ov = self.overrides
        law = ov.get(LAW_KEY)
        if law is None and isinstance(ov.get("controller"), dict):
            law = ov["controller"].get("law")
        if law is None and self.run is not None:
            law = ((self.run.scenario or {}).get("controller") or {}).get("law")
        return None if law is None else str(law)

    @property
    def short(self) -> str:
        return "/".join(fmt(v) for v in self.params.values()) or self.id

    @property
    def status(self) -> str:
        if self.run is None:
            return "not run"
        return self.run.status

    @property
    def life_km(self) -> float | None:
        fs = self.run.fatigue if self.run else None
        v = (fs or {}).get("min_life_km")
        return float(v) if is_num(v) else None

    @property
    def label(self) -> str:
        return ", ".join(f"{k.split('.')[-1]}={fmt(v)}" for k, v in self.params.items()) or self.id


def load_sweep(d: Path, runs_dir: Path | None = None) -> tuple[dict, list[Point]]:
    """sweep.json and its points (BadInput if unreadable)."""
    p = d / "sweep.json"
    try:
        spec = json.loads(read_user_text(p, "scenario", inside=d))
    except (SuscosimError, OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise BadInput(f"{p}: unreadable ({exc})") from None
    if not isinstance(spec, dict) or not isinstance(spec.get("points", []), list):
        raise BadInput(f"{p}: expected an object with a 'points' list")
    points = []
    for i, pt in enumerate(spec.get("points", [])):
        if not isinstance(pt, dict):
            raise BadInput(f"{p}: points[{i}] is not an object")
        pid = str(pt.get("id", i))
        params = pt.get("params") or {}
        if not isinstance(params, dict):
            raise BadInput(f"{p}: points[{i}].params is not an object")
        rd = d / str(pt.get("run_dir") or f"runs/{pid}")
        if not any(_inside(rd, top) for top in (d, runs_dir) if top is not None):
            raise BadInput(f"{p}: points[{i}].run_dir {str(pt.get('run_dir'))!r:.200} leaves "
                           "the sweep folder (only run folders inside it are read; a shared "
                           "runs folder is read when named: suscosim report DIR --runs-dir R)")
        run = load_run(rd) if rd.is_dir() and is_run_dir(rd) else None
        ov = pt.get("overrides")
        points.append(Point(pid, params, rd, run, ov if isinstance(ov, dict) else {}))
    return spec, points


def _inside(path: Path, top: Path) -> bool:
    real = os.path.realpath(top)
    return os.path.commonpath([os.path.realpath(path), real]) == real


def read_results(d: Path) -> tuple[list[dict], str]:
    """Rows of results.json (list, or object with 'rows'/'points') or results.csv."""
    pj, pc = d / "results.json", d / "results.csv"
    if pj.is_file():
        try:
            data = json.loads(read_user_text(pj, "report", inside=d))
        except (OSError, ValueError) as exc:  # InputFileError, UnicodeDecodeError, JSON
            return [], f"results.json unreadable ({exc})"
        if isinstance(data, dict):
            data = data.get("rows", data.get("points", data.get("results", [])))
        if isinstance(data, list) and all(isinstance(x, dict) for x in data):
            return data, "results.json"
        return [], "results.json: not a list of rows"
    if pc.is_file():
        try:
            with open_user_text(pc, "report", inside=d) as fh:
                return list(csv.DictReader(fh)), "results.csv"
        except (OSError, ValueError, csv.Error) as exc:  # ValueError: InputFileError too
            return [], f"results.csv unreadable ({exc})"
    return [], ""


def grid_keys(spec: dict, points: list[Point]) -> list[str]:
    grid = spec.get("grid")
    keys = list(grid) if isinstance(grid, dict) else []
    for p in points:
        keys += [k for k in p.params if k not in keys]
    return keys


def rms_of(p: Point, bases: Sequence[str]) -> float | None:
    if p.run is None:
        return None
    chans = (p.run.summary or {}).get("channels") or {}
    for b in bases:
        for name in (b, f"{b}[0]"):
            if name in chans and is_num(chans[name].get("rms")):
                return float(chans[name]["rms"])
    if p.run.table is not None:
        _b, cols = first_present(p.run.table, bases)
        if cols:
            x = cols[0][1]
            return float(np.sqrt(np.mean(x * x)))
    return None


def law_axis(points: list[Point], keys: list[str]) -> str | None:
    """``controller.law``, or an axis whose every value gives one law, passive among them."""
    if LAW_KEY in keys:
        return LAW_KEY
    for k in keys:
        laws: dict[str, set] = {}
        for p in points:
            if k in p.params and p.law is not None:
                laws.setdefault(json.dumps(p.params[k], sort_keys=True, default=str),
                                set()).add(p.law)
        distinct = set().union(*laws.values()) if laws else set()
        if laws and all(len(v) == 1 for v in laws.values()) and len(distinct) > 1 \
                and PASSIVE in distinct:
            return k
    return None


def is_passive(p: Point, axis: str) -> bool:
    return p.law == PASSIVE or p.params.get(axis) == PASSIVE


def vs_passive(points: list[Point], keys: list[str], value) -> dict[str, float]:
    """``{id: (value / the passive point's of its grid cell - 1) * 100}`` (no law axis: {})."""
    axis = law_axis(points, keys)
    if axis is None:
        return {}
    others = [k for k in keys if k != axis]

    def cell(p: Point) -> tuple:
        return tuple(json.dumps(p.params.get(k), sort_keys=True, default=str) for k in others)

    base: dict[tuple, float | None] = {}
    for p in points:
        if is_passive(p, axis) and cell(p) not in base:
            base[cell(p)] = value(p)
    out = {}
    for p in points:
        b, v = base.get(cell(p)), value(p)
        if b is not None and v is not None and b > 0:
            out[p.id] = (v / b - 1.0) * 100.0
    return out
