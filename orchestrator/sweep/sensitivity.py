"""The sensitivity table of a sampled design (``sensitivity.csv``/``.json``): per grid point
(``group``), each output (minimum life, ride metrics) against each sampled parameter: Spearman
rho (p-value) and PRCC (any design; monotonic association, not variance shares); Sobol' S1, ST
with 95 % bootstrap confidence (SALib) for ``method = "saltelli"`` when the group all succeeded.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from cosim.run_folder import replaced

from .spec import AXIS, Sweep

COLUMNS = ("output", "parameter", "n", "spearman", "spearman_p", "prcc", "S1", "S1_conf",
           "ST", "ST_conf")
_RANKS = ("Spearman and partial rank correlations (monotonic association, not variance shares); "
          "Sobol' indices need method = \"saltelli\" and are not given.")
VALIDITY = {
    "lhs": "Latin hypercube: " + _RANKS, "sobol": "Sobol' sequence: " + _RANKS,
    "saltelli": "Saltelli's design: Sobol' indices S1/ST (variance shares, SALib) and, on the "
                "same points, rank correlations (Saltelli's points are not independent "
                "samples: their p-values are indicative only).",
}


def outputs_of(sweep: Sweep, rows: list[dict]) -> list[str]:
    outs = ["life_km"] if sweep.fatigue else []
    for r in rows:
        outs += [c for c in r if c.startswith("ride ") and c not in outs]
    return outs


def _finite(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def rank_correlations(x: np.ndarray, y: np.ndarray) -> list[tuple[float, float, float]]:
    """Per column of ``x`` (n, d): (Spearman rho, p, PRCC) with ``y`` (n,); NaN if undefined."""
    from scipy.stats import rankdata, spearmanr

    n, d = x.shape
    out = []
    if n < 3 or np.ptp(y) == 0:
        return [(math.nan, math.nan, math.nan)] * d
    rx = np.column_stack([rankdata(x[:, j]) for j in range(d)])
    ry = rankdata(y)
    for j in range(d):
        if np.ptp(x[:, j]) == 0:
            out.append((math.nan, math.nan, math.nan))
            continue
        rho, p = spearmanr(x[:, j], y)
        others = np.column_stack([np.ones(n), np.delete(rx, j, axis=1)])
        if n <= others.shape[1] + 1:
            prcc = math.nan
        else:
            res_x = rx[:, j] - others @ np.linalg.lstsq(others, rx[:, j], rcond=None)[0]
            res_y = ry - others @ np.linalg.lstsq(others, ry, rcond=None)[0]
            den = math.sqrt(float(res_x @ res_x) * float(res_y @ res_y))
            prcc = float(res_x @ res_y) / den if den > 0 else math.nan
        out.append((float(rho), float(p), prcc))
    return out


def sobol_indices(problem: dict[str, Any], y: np.ndarray, seed: int) -> dict[str, np.ndarray]:
    from SALib.analyze import sobol

    res = sobol.analyze(problem, y, calc_second_order=False, print_to_console=False, seed=seed)
    return {k: np.asarray(res[k], dtype=float) for k in ("S1", "S1_conf", "ST", "ST_conf")}


def sensitivity(sweep: Sweep, rows: list[dict]) -> dict[str, Any]:
    design = sweep.design
    assert design is not None
    params = design.keys
    group_axes = [a.name for a in sweep.axes if a.name != AXIS]
    outputs = outputs_of(sweep, rows)
    groups: dict[tuple, list[dict]] = {}
    for r in rows:
        groups.setdefault(tuple(r.get(a) for a in group_axes), []).append(r)
    table = []
    for gkey, grows in groups.items():
        group = dict(zip(group_axes, gkey, strict=True))
        for out in outputs:
            ok = [r for r in grows if r.get("status") == "ok" and _finite(r.get(out))
                  and all(_finite(r.get(k)) for k in params)]
            x = np.array([[float(r[k]) for k in params] for r in ok]).reshape(len(ok), len(params))
            y = np.array([float(r[out]) for r in ok])
            corr = rank_correlations(x, y)
            sob = None
            if design.method == "saltelli" and len(ok) == len(grows) and np.ptp(y) > 0:
                problem = {"num_vars": len(params), "names": params,
                           "bounds": [[0.0, 1.0]] * len(params)}
                sob = sobol_indices(problem, y, design.seed)
            for j, k in enumerate(params):
                rho, p, prcc = corr[j]
                entry: dict[str, Any] = {**group, "output": out, "parameter": k,
                                         "n": len(ok), "spearman": rho, "spearman_p": p,
                                         "prcc": prcc}
                for c in ("S1", "S1_conf", "ST", "ST_conf"):
                    entry[c] = float(sob[c][j]) if sob is not None else None
                table.append(entry)
    return {"method": design.method, "seed": design.seed, "n_points": len(rows),
            "parameters": params, "outputs": outputs, "group_axes": group_axes,
            "validity": VALIDITY[design.method], "rows": table}


def write_sensitivity(out: Path, sens: dict[str, Any]) -> None:
    from ..runner import strict_json

    rows = strict_json(sens["rows"])
    with replaced(out / "sensitivity.json") as fh:
        fh.write(json.dumps({**sens, "rows": rows}, indent=2))
    columns = [*sens["group_axes"], *COLUMNS]
    with replaced(out / "sensitivity.csv", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=columns, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({c: "" if r.get(c) is None else r.get(c) for c in columns})


def sensitivity_table(sens: dict[str, Any]) -> str:
    sobol = sens["method"] == "saltelli"
    head = [*sens["group_axes"], "output", "parameter", "n", "spearman", "prcc"]
    head += ["S1", "ST"] if sobol else []

    def fmt(v: Any) -> str:
        if v is None or (isinstance(v, float) and not math.isfinite(v)):
            return "-"
        return f"{v:+.3f}" if isinstance(v, float) else str(v)

    body = [[fmt(r.get(c)) for c in head] for r in sens["rows"]]
    widths = [max(len(h), *(len(b[i]) for b in body)) if body else len(h)
              for i, h in enumerate(head)]
    lines = [f"sensitivity ({sens['method']} design, {sens['n_points']} points): "
             + sens["validity"],
             "  ".join(h.ljust(w) for h, w in zip(head, widths, strict=True)),
             "  ".join("-" * w for w in widths)]
    lines += ["  ".join(v.ljust(w) for v, w in zip(b, widths, strict=True)) for b in body]
    return "\n".join(lines)
