"""The sweep page's sensitivity section, for a sampled design (``[sweep.design]``): what the
table is valid for, the rank correlations (and Sobol' indices for Saltelli's design) of each
output with each parameter from ``sensitivity.json``, and each output against each parameter
from the results rows."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from cosim.safe_open import read_user_text

from .markup import esc, note, section, table_html
from .plots import fig_uri, img, new_figure

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
    """(sensitivity.json or None, a problem with it or "")."""
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
    """The section, or "" for a sweep without a sampled design."""
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
