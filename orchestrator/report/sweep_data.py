"""The sweep as the report reads it from its folder (sweep.json, runs/<id>/, results; files
only, no :mod:`orchestrator.sweep`): points, grid axes, the law axis, changes against passive;
and the sweep page's charts: life and body acceleration per point and against passive,
overlaid PSDs and time histories, damage maps side by side."""

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

from .markup import anchor_id, esc, fmt, is_num, note, section
from .plots import decimate, fig_uri, file_uri, img, new_figure
from .signals import BODY_ACC, PSD_F_MAX_HZ, TYRE_FORCE, first_present, sample_rate, welch_psd
from .stream import BadInput, RunData, is_run_dir, load_run

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
        return "not run" if self.run is None else self.run.status

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

    base = {cell(p): value(p) for p in reversed(points) if is_passive(p, axis)}  # the first
    out = {}
    for p in points:
        b, v = base.get(cell(p)), value(p)
        if b is not None and v is not None and b > 0:
            out[p.id] = (v / b - 1.0) * 100.0
    return out


def _bars(ax, labels: list[str], values: list[float | None], title: str, ylabel: str,
          log: bool = False, colors: list[str] | None = None) -> None:
    """One bar per point; ``log``: a log axis only when the values span > 50x."""
    x = np.arange(len(labels))
    vals = [v if v is not None else np.nan for v in values]
    colors = colors or [f"C{i % 10}" for i in range(len(labels))]
    bars = ax.bar(x, vals, color=colors, width=0.6)
    ax.bar_label(bars, labels=[fmt(v) if v is not None else "" for v in values], fontsize=7)
    tilt = len(labels) > 4
    ax.set_xticks(x, labels, rotation=30 if tilt else 0, ha="right" if tilt else "center",
                  fontsize=8)
    pos = [v for v in values if v is not None and v > 0]
    if log and pos and max(pos) / min(pos) > 50:
        ax.set_yscale("log")
    ax.set_xlim(-0.7, len(labels) - 0.3)
    ax.set_title(title, fontsize=10, loc="left")
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3, axis="y")
    for xi, v in zip(x, values, strict=True):
        if v is None:
            ax.annotate("n/a", (xi, 0), xytext=(0, 2), textcoords="offset points",
                        ha="center", va="bottom", fontsize=8, color="#888")


def law_colours(points: list[Point], axis: str) -> dict[str, str]:
    vals = [fmt(x) for x in dict.fromkeys(p.params.get(axis) for p in points)]
    passive = {fmt(p.params.get(axis)) for p in points if is_passive(p, axis)}
    vals.sort(key=lambda v: v not in passive)
    return {v: f"C{i % 10}" for i, v in enumerate(vals)}


def _point_colours(points: list[Point], keys: list[str]) -> list[str] | None:
    axis = law_axis(points, keys)
    if axis is None:
        return None
    colour = law_colours(points, axis)
    return [colour[fmt(p.params.get(axis))] for p in points]


def _cell_label(p: Point, others: list[str]) -> str:
    return ", ".join(f"{k.split('.')[-1]}={fmt(p.params.get(k))}" for k in others) or "all"


def _grouped_change(ax, points: list[Point], keys: list[str], change: dict[str, float],
                    title: str) -> None:
    """Bars of ``change`` [%] per law, grouped by the grid cell of the other parameters."""
    axis = law_axis(points, keys) or LAW_KEY
    others = [k for k in keys if k != axis]
    colour = law_colours(points, axis)
    laws = [law for law in dict.fromkeys(fmt(p.params.get(axis)) for p in points
                                         if not is_passive(p, axis))
            if any(q.id in change for q in points if fmt(q.params.get(axis)) == law)]
    cells = list(dict.fromkeys(_cell_label(p, others) for p in points))
    value = {(_cell_label(p, others), fmt(p.params.get(axis))): change.get(p.id) for p in points}
    nl = max(1, len(laws))
    width = min(0.8 / nl, 0.35)
    for j, law in enumerate(laws):
        ys = [value.get((c, law)) for c in cells]
        xs = np.arange(len(cells)) * (1 if len(cells) > 1 else 0) + \
            (j - (nl - 1) / 2) * (width if len(cells) > 1 else 0.5)
        bars = ax.bar(xs, [np.nan if y is None else y for y in ys], width=width,
                      label=str(law), color=colour[str(law)])
        ax.bar_label(bars, labels=[f"{y:+.1f} %" if y is not None else "" for y in ys], fontsize=7)
    if len(cells) > 1:
        ax.set_xticks(np.arange(len(cells)), cells, fontsize=8)
        ax.set_xlim(-0.7, len(cells) - 0.3)
        ax.legend(fontsize=8)
    else:
        ticks = [(j - (nl - 1) / 2) * 0.5 for j in range(nl)]
        ax.set_xticks(ticks, [str(x) for x in laws], fontsize=8)
        ax.set_xlim(min(ticks, default=0) - 0.5, max(ticks, default=0) + 0.5)
    ax.axhline(0, color="k", lw=0.8)
    ax.margins(y=0.15)
    ax.set_title(title, fontsize=10, loc="left")
    ax.set_ylabel("% vs passive")
    ax.grid(alpha=0.3, axis="y")


def sweep_compare_section(points: list[Point], keys: list[str]) -> str:
    lives = [p.life_km for p in points]
    accs = [rms_of(p, BODY_ACC) for p in points]
    labels = [p.short for p in points]
    life_change = vs_passive(points, keys, lambda p: p.life_km)
    acc_change = vs_passive(points, keys, lambda p: rms_of(p, BODY_ACC))
    colours = _point_colours(points, keys)

    def chart(values: list, change: dict[str, float], title: str, unit: str, change_title: str,
              row_h: float, log: bool = False) -> str:
        fig, axes = new_figure(1, 2 if change else 1, row_h=row_h)
        _bars(axes[0], labels, values, title, unit, log=log, colors=colours)
        if change:
            _grouped_change(axes[1], points, keys, change, change_title)
        return fig_uri(fig)
    body = ""
    if any(v is not None for v in lives):
        body += "<h3>Fatigue</h3>" + img(chart(lives, life_change, "Minimum life of the lower "
                                               "arm", "km", "Life change vs passive", 3.8,
                                               log=True), "minimum life per point")
        if life_change:
            body += '<p class="meta">life change vs passive = (life / life of the passive ' \
                    "point with the same other grid parameters − 1) × 100 %.</p>"
    else:
        body += note("no fatigue results in any point: run <code>suscosim fatigue "
                     "SWEEP/runs/&lt;id&gt;</code> for each point (or give the sweep a "
                     "realistic corner, whose runs carry arm loads).")
    if any(v is not None for v in accs):
        body += "<h3>Ride</h3>" + img(chart(accs, acc_change, "Body acceleration RMS", "m/s²",
                                            "Body acceleration RMS change", 3.4),
                                      "body acceleration RMS per point")
    return section("compare", "Comparison", body)


def overlay_groups(points: list[Point], keys: list[str]
                   ) -> list[tuple[str, list[tuple[Point, str, str]]]]:
    """``[(title, [(point, label, colour)])]``: a group per cell of the non-law axes."""
    axis = law_axis(points, keys)
    if axis is None:
        return [("", [(p, p.short, f"C{j % 10}") for j, p in enumerate(points)])]
    colour = law_colours(points, axis)
    others = [k for k in keys if k != axis]
    groups: dict[str, list[tuple[Point, str, str]]] = {}
    for p in points:
        v = fmt(p.params.get(axis))
        groups.setdefault(_cell_label(p, others) if others else "", []).append((p, v, colour[v]))
    return list(groups.items())


def _table_of(p: Point) -> dict[str, np.ndarray]:
    assert p.run is not None and p.run.table is not None, f"point {p.id} has no table"
    return p.run.table


def _overlay_figures(members: list[tuple[Point, str, str]], ci: int) -> str:
    out = ""
    fig, axes = new_figure(1, 1, row_h=3.4)
    ax = axes[0]
    corner, n_psd = "", 0
    for p, lab, colour in members:
        tab = _table_of(p)
        fs = sample_rate(tab["t"])
        _b, cols = first_present(tab, BODY_ACC)
        if fs is None or len(cols) <= ci:
            continue
        corner, x = cols[ci]
        f, pp = welch_psd(x, fs)
        keep = (f > 0) & (f <= min(fs / 2, PSD_F_MAX_HZ))
        ax.semilogy(f[keep], np.maximum(pp[keep], 1e-30), lw=1.0, color=colour, label=lab)
        n_psd += 1
    if n_psd:
        ax.set_title("Body acceleration PSD" + (f" ({corner})" if corner else ""),
                     fontsize=10, loc="left")
        ax.set_xlabel("f [Hz]")
        ax.set_ylabel("(m/s²)²/Hz")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
        out += img(fig_uri(fig), "overlaid body acceleration PSDs")
    rows = [("Body acceleration", "m/s²", BODY_ACC), ("Tyre force", "N", TYRE_FORCE)]
    if any(p.run is not None and p.run.has_arm() for p, _l, _c in members):
        rows.append(("Lower arm: ball joint z", "N", ("plant/arm/ball_joint_z",)))
    fig, axes = new_figure(len(rows), row_h=2.4, sharex=True)
    for ax, (title, unit, bases) in zip(axes, rows, strict=True):
        for p, lab, colour in members:
            tab = _table_of(p)
            _b, cols = first_present(tab, bases)
            if len(cols) > ci:
                ax.plot(*decimate(tab["t"], cols[ci][1]), lw=0.8, color=colour, label=lab,
                        alpha=0.85)
        ax.set_title(title + (f" ({corner})" if corner else ""), fontsize=10, loc="left")
        ax.set_ylabel(unit)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right", ncol=min(4, len(members)))
    axes[-1].set_xlabel("t [s]")
    return out + img(fig_uri(fig), "overlaid time histories")


def sweep_overlay_section(points: list[Point], keys: list[str]) -> str:
    have = [p for p in points if p.run is not None and p.run.table is not None]
    if not have:
        return section("overlay", "PSDs and time histories of the points",
                       note("no point has a table yet."))
    # the corner with the largest body-acceleration RMS in the first point (full vehicle)
    ci = 0
    _b, cols = first_present(_table_of(have[0]), BODY_ACC)
    if len(cols) > 1:
        ci = int(np.argmax([np.sqrt(np.mean(x * x)) for _c, x in cols]))
    body = ""
    for title, members in overlay_groups(have, keys):
        if title:
            body += f"<h3>{esc(title)}</h3>"
        body += _overlay_figures(members, ci)
    return section("overlay", "PSDs and time histories of the points", body)


def sweep_maps_section(points: list[Point]) -> str:
    figs = []
    missing = []
    for p in points:
        uri = file_uri(p.run.damage_map) if p.run and p.run.damage_map else None
        if uri:
            life = f" · min life {fmt(p.life_km)} km" if p.life_km is not None else ""
            figs.append(f'<figure>{img(uri, f"damage map {p.id}")}<figcaption>'
                        f'<a href="#{anchor_id(p.id)}">{esc(p.id)}</a> · {esc(p.label)}'
                        f"{esc(life)}</figcaption></figure>")
        else:
            missing.append(p.id)
    body = f'<div class="maps">{"".join(figs)}</div>' if figs else ""
    if missing:
        body += note("no damage map for: " + esc(", ".join(missing)))
    return section("maps", "Damage maps of the lower arm", body)
