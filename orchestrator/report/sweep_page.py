"""The sweep page: its header, results table, the sensitivity of a sampled design
(``[sweep.design]``: sensitivity.json's rank correlations and Sobol' indices, each output
against each parameter), one section per point; the charts are :mod:`.sweep_data`'s."""

from __future__ import annotations

import datetime as _dt
import json
import math
from collections import Counter
from pathlib import Path
from typing import Any

from cosim.safe_open import read_user_text

from . import sweep_data as sd
from .fatigue_section import fatigue_numbers
from .markup import anchor_id, badge, cmd, esc, kv_table, nav, note, page, section, table_html
from .plots import fig_uri, img, new_figure
from .signals import BODY_ACC, TYRE_FORCE
from .sweep_data import Point, grid_keys, load_sweep, read_results, rms_of, vs_passive

MAX_SCATTER_OUTPUTS = 4
"""Outputs drawn against each parameter (the table lists them all)."""


def _num(v: Any) -> float | None:
    try:
        x = float(v)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def _conf(v: Any, c: Any) -> str:
    x, e = _num(v), _num(c)
    if x is None:
        return "–"
    return f"{x:.3f} ± {e:.3f}" if e is not None else f"{x:.3f}"


def read_sensitivity(d: Path) -> tuple[dict[str, Any] | None, str]:
    path = d / "sensitivity.json"
    if not path.is_file():
        return None, ""
    try:
        sens = json.loads(read_user_text(path, "report", inside=d))
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        return None, f"sensitivity.json unreadable ({exc})"
    if not isinstance(sens, dict) or not isinstance(sens.get("rows"), list):
        return None, "sensitivity.json: no 'rows' list"
    return sens, ""


def sensitivity_section(d: Path, results: list[dict]) -> str:
    sens, problem = read_sensitivity(d)
    if sens is None:
        return section("sensitivity", "Sensitivity", note(esc(problem))) if problem else ""
    groups = [str(g) for g in sens.get("group_axes") or []]
    sobol = sens.get("method") == "saltelli"
    head = [*groups, "output", "parameter", "n", "Spearman ρ", "p", "PRCC"]
    head += ["S1 (95 %)", "ST (95 %)"] if sobol else []
    rows = []
    for r in sens["rows"]:
        row: list[Any] = [*(r.get(g) for g in groups), r.get("output"), r.get("parameter"),
                          r.get("n"), _num(r.get("spearman")), _num(r.get("spearman_p")),
                          _num(r.get("prcc"))]
        if sobol:
            row += [_conf(r.get("S1"), r.get("S1_conf")), _conf(r.get("ST"), r.get("ST_conf"))]
        rows.append(row)
    body = (f"<p>{esc(str(sens.get('method')))} design, seed {esc(str(sens.get('seed')))}, "
            f"{esc(str(sens.get('n_points')))} points. {esc(str(sens.get('validity', '')))}"
            "</p>" + table_html(head, rows))
    params = [str(p) for p in sens.get("parameters") or []]
    outputs = [str(o) for o in sens.get("outputs") or []][:MAX_SCATTER_OUTPUTS]
    ok = [r for r in results if r.get("status") == "ok"]
    if params and outputs and ok:
        fig, axes = new_figure(len(outputs), len(params), width=4.0 * len(params) + 1.0, row_h=2.6)
        for i, out in enumerate(outputs):
            for j, p in enumerate(params):
                ax = axes[i * len(params) + j]
                pts = [(_num(r.get(p)), _num(r.get(out))) for r in ok]
                xs = [x for x, y in pts if x is not None and y is not None]
                ys = [y for x, y in pts if x is not None and y is not None]
                ax.plot(xs, ys, "o", ms=4, color="#4472c4")
                ax.set_xlabel(p)
                ax.set_ylabel(out)
        body += img(fig_uri(fig), "each output against each sampled parameter")
    return section("sensitivity", "Sensitivity", body)


def sweep_results_section(spec: dict, points: list[Point], keys: list[str], d: Path) -> str:
    life_change = vs_passive(points, keys, lambda p: p.life_km)
    acc_change = vs_passive(points, keys, lambda p: rms_of(p, BODY_ACC))
    header = ["point", *keys, "status", "wall [s]", "steps/s", "a_b rms [m/s²]",
              "F_t rms [N]", "min life [km]"]
    if life_change:
        header.append("life change vs passive [%]")
    if acc_change:
        header.append("a_b rms vs passive [%]")
    header.append("error")
    rows = []
    for p in points:
        s = (p.run.summary or {}) if p.run else {}
        row: list[Any] = [f'<a href="#{anchor_id(p.id)}">{esc(p.id)}</a>',
                          *[p.params.get(k) for k in keys], badge(p.status),
                          s.get("wall_s"), s.get("steps_per_s"), rms_of(p, BODY_ACC),
                          rms_of(p, TYRE_FORCE), p.life_km]
        row += [change.get(p.id) for change in (life_change, acc_change) if change]
        err = s.get("error") or ("" if p.run else f"no run folder {p.run_dir}")
        row.append(err[:160] + ("…" if len(err) > 160 else ""))
        rows.append(row)
    body = table_html(header, rows, raw_cols=(0, 1 + len(keys)))  # the link, the status
    results, src = read_results(d)
    if results:
        cols = list(dict.fromkeys(k for res in results for k in res))
        body += (f"<details><summary>{esc(src)}: every column ({len(cols)})</summary>"
                 + table_html(cols, [[_num_or_text(r.get(c)) for c in cols] for r in results])
                 + "</details>")
    elif src:
        body += note(esc(src))
    else:
        body += note("no results.json / results.csv in the sweep folder (the sweep has not "
                     "finished); the table above is read from the run folders.")
    return section("results", "Results", body)


def _num_or_text(v: Any) -> Any:
    if isinstance(v, str):
        try:
            return float(v) if v.strip() else v
        except ValueError:
            return v
    return v


def point_section(p: Point, d: Path) -> str:
    parts = [f'<section id="{anchor_id(p.id)}"><h3>Point {esc(p.id)} {badge(p.status)}</h3>']
    parts.append(kv_table(list(p.params.items()) or [("params", "none")]))
    try:
        rel = p.run_dir.relative_to(d)
    except ValueError:
        rel = p.run_dir
    parts.append(f'<p class="meta">run folder {cmd(str(rel))}')
    if (p.run_dir / "report.html").is_file():
        parts.append(f' · <a href="{esc((rel / "report.html").as_posix())}">its own report</a>')
    else:
        parts.append(f" · its own report: {cmd(f'suscosim report {p.run_dir}')}")
    parts.append("</p>")
    if p.run is None:
        parts.append(note("not run yet (no run folder)."))
    else:
        s = p.run.summary or {}
        if s.get("error"):
            parts.append(f'<div class="error">{esc(s["error"])}</div>')
        pairs = [(k, s.get(k)) for k in ("wall_s", "steps_per_s", "n_steps", "rows") if k in s]
        pairs += [("a_b rms [m/s²]", rms_of(p, BODY_ACC)), ("F_t rms [N]", rms_of(p, TYRE_FORCE))]
        if p.run.fatigue:
            pairs += fatigue_numbers(p.run.fatigue)[:5]
        else:
            pairs.append(("fatigue", "no results"))
        parts.append(kv_table(pairs))
    parts.append('<p class="meta"><a href="#results">back to the results</a></p></section>')
    return "".join(parts)


def render_sweep(d: Path, runs_dir: Path | None = None) -> str:
    spec, points = load_sweep(d, runs_dir)
    keys = grid_keys(spec, points)
    name = str(spec.get("name") or d.name)
    counts = Counter(p.status for p in points)
    head = [f"<h1>Sweep {esc(name)}</h1>",
            f'<p class="meta">folder {cmd(str(d.resolve()))} · report written '
            f"{esc(_dt.datetime.now().strftime('%Y-%m-%d %H:%M:%S'))}</p>"]
    pairs = [("base scenario", spec.get("base")), ("points", len(points)),
             ("status", ", ".join(f"{v} {k}" for k, v in counts.items()) or "none")]
    grid = spec.get("grid")
    if isinstance(grid, dict):
        pairs += [(f"grid: {k}", v) for k, v in grid.items()]
    st = spec.get("set")
    if isinstance(st, dict):
        pairs += [(f"set: {k}", v) for k, v in st.items()]
    elif st:
        pairs.append(("set", st))
    head.append(kv_table(pairs))
    if not points:
        head.append(note("sweep.json lists no points."))
    sens = sensitivity_section(d, read_results(d)[0])
    navs = [("results", "Results"), *([("sensitivity", "Sensitivity")] if sens else []),
            ("compare", "Comparison"), ("overlay", "PSDs / histories"),
            ("maps", "Damage maps"), ("points", "Points")]
    body = "".join(head) + nav(navs) + sweep_results_section(spec, points, keys, d) + sens + \
        sd.sweep_compare_section(points, keys) + sd.sweep_overlay_section(points, keys) + \
        sd.sweep_maps_section(points) + \
        section("points", "Points", "".join(point_section(p, d) for p in points))
    return page(f"suscosim sweep {name}", body)
