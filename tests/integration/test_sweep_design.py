"""Sampled designs of experiments in ``suscosim sweep`` (``[sweep.design]``) and their
sensitivity table: the designs' properties and errors, the estimators on functions whose
answer is known, and a 16-point Latin hypercube of real runs over two damper parameters."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import spearmanr

from orchestrator.sweep import load_sweep
from orchestrator.sweep.sensitivity import sensitivity

from ..conftest import CH3_STEP, suscosim

DESIGN = f"""
[sweep]
name = "tdoe"
base = "{CH3_STEP}"
jobs = 2
[sweep.design]
method = "METHOD"
n = N
seed = 3
[sweep.design.ranges]
"controller.c_soft" = [500.0, 1500.0]
"controller.c_hard" = [2000.0, 5000.0]
[sweep.set]
controller = {{ law = "tss1" }}
"run.t_end" = 0.5
"road.t_start" = 0.1
"run.stall_timeout_s" = 30.0
"run.mode" = "monolithic"
"""
KEYS = ("controller.c_soft", "controller.c_hard")


def _file(tmp_path: Path, method: str = "lhs", n: int = 16, extra: str = "") -> Path:
    f = tmp_path / f"{method}{n}.toml"
    f.write_text(DESIGN.replace("METHOD", method).replace("N", str(n)) + extra)
    return f


def test_latin_hypercube_is_seeded_stratified_and_in_range(tmp_path):
    sweep = load_sweep(_file(tmp_path))
    assert [p.id for p in sweep.points][:2] == ["tdoe-s000", "tdoe-s001"]
    x = np.array([[p.params[k] for k in KEYS] for p in sweep.points])
    assert x.shape == (16, 2)
    for j, (lo, hi) in enumerate(((500.0, 1500.0), (2000.0, 5000.0))):
        assert np.all((x[:, j] >= lo) & (x[:, j] <= hi))
        strata = np.floor((x[:, j] - lo) / (hi - lo) * 16).clip(0, 15)
        assert sorted(strata) == list(range(16))  # one sample in each of the 16 strata
    p = sweep.points[5]
    assert p.overrides["controller.c_soft"] == p.params["controller.c_soft"]
    assert p.overrides["controller"] == {"law": "tss1"}
    again = load_sweep(_file(tmp_path))
    assert [q.params for q in again.points] == [q.params for q in sweep.points]
    f4 = tmp_path / "seed4.toml"
    f4.write_text(_file(tmp_path).read_text().replace("seed = 3", "seed = 4"))
    other = load_sweep(f4)
    assert [q.params for q in other.points] != [q.params for q in sweep.points]


def test_sobol_and_saltelli_designs_and_their_sizes(tmp_path):
    sob = load_sweep(_file(tmp_path, "sobol", 16))
    assert len(sob.points) == 16
    sal = load_sweep(_file(tmp_path, "saltelli", 8))
    assert len(sal.points) == 8 * (2 + 2)  # N (D + 2) without second-order indices


@pytest.mark.integration
def test_bad_designs_exit_2_naming_the_key(tmp_path):
    res = suscosim("sweep", str(_file(tmp_path, "sobol", 12)), "--list")
    assert res.returncode == 2 and "sweep.design.n" in res.stderr and "power of 2" in res.stderr
    bad = _file(tmp_path).read_text().replace('[2000.0, 5000.0]', '[5000.0, 2000.0]')
    (tmp_path / "b.toml").write_text(bad)
    res = suscosim("sweep", str(tmp_path / "b.toml"), "--list")
    assert res.returncode == 2 and "controller.c_hard" in res.stderr, res.stderr
    bad = _file(tmp_path).read_text().replace('method = "lhs"', 'method = "grid"')
    (tmp_path / "m.toml").write_text(bad)
    res = suscosim("sweep", str(tmp_path / "m.toml"), "--list")
    assert res.returncode == 2 and "sweep.design.method" in res.stderr, res.stderr
    assert "Traceback" not in res.stderr


def _rows(sweep, f) -> list[dict]:
    """Result rows of a design whose 'ride y' output is the function f of the parameters."""
    rows = []
    for p in sweep.points:
        x = [(p.params[k] - lo) / (hi - lo) for k, (lo, hi) in
             zip(KEYS, ((500.0, 1500.0), (2000.0, 5000.0)), strict=True)]
        rows.append({"point": p.id, **p.params, "status": "ok", "ride y": f(*x)})
    return rows


def test_sobol_indices_of_a_known_function_and_rank_correlations(tmp_path):
    # y = 3 a + b on the unit square: S1 = ST = 9/10 and 1/10 (variances 9/12 and 1/12)
    sal = load_sweep(_file(tmp_path, "saltelli", 512))
    sens = sensitivity(sal, _rows(sal, lambda a, b: 3 * a + b))
    by = {r["parameter"]: r for r in sens["rows"]}
    assert by[KEYS[0]]["S1"] == pytest.approx(0.9, abs=0.05)
    assert by[KEYS[1]]["ST"] == pytest.approx(0.1, abs=0.05)
    assert "Sobol' indices" in sens["validity"]
    # a Latin hypercube: rank correlations only (no Sobol' indices: not its design)
    lhs = load_sweep(_file(tmp_path, "lhs", 64))
    rows = _rows(lhs, lambda a, b: np.exp(4 * a) - b)
    sens = sensitivity(lhs, rows)
    by = {r["parameter"]: r for r in sens["rows"]}
    for k in KEYS:
        rho = spearmanr([r[k] for r in rows], [r["ride y"] for r in rows])[0]
        assert by[k]["spearman"] == pytest.approx(rho, rel=1e-12)
        assert by[k]["S1"] is None
    assert by[KEYS[0]]["prcc"] > 0.95 and by[KEYS[1]]["prcc"] < -0.5
    rows[3]["status"] = "failed"  # a failed point is left out, not counted
    assert sensitivity(lhs, rows)["rows"][0]["n"] == 63


@pytest.mark.integration
def test_16_point_latin_hypercube_of_real_runs_with_its_sensitivity_table(tmp_path):
    """16 real lumped quarter-car runs (monolithic mode: the node code in one process, to
    keep the test short), TSS1 over the step, c_soft and c_hard sampled."""
    out = tmp_path / "sw"
    res = suscosim("sweep", str(_file(tmp_path)), "--out", str(out), timeout=600)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "sensitivity (lhs design, 16 points)" in res.stdout
    rows = json.loads((out / "results.json").read_text())
    assert len(rows) == 16 and all(r["status"] == "ok" for r in rows)
    for r in rows:  # each run really had its sample's damping
        scen = json.loads((out / r["run_dir"] / "scenario.json").read_text())
        assert scen["controller"]["c_soft"] == r["controller.c_soft"]
        assert scen["controller"]["c_hard"] == r["controller.c_hard"]
        assert r["ride f_d_rms"] > 0 and r["ride a_b_rms"] > 0
    sens = json.loads((out / "sensitivity.json").read_text())
    assert sens["method"] == "lhs" and sens["parameters"] == list(KEYS)
    assert {"ride a_b_rms", "ride a_w_rms", "ride sws", "ride dtl_rms",
            "ride f_d_rms"} <= set(sens["outputs"])
    with open(out / "sensitivity.csv", newline="") as fh:
        table = list(csv.DictReader(fh))
    assert len(table) == 2 * len(sens["outputs"])
    by = {(r["output"], r["parameter"]): r for r in table}
    for (output, k), r in by.items():  # the table is the rank correlation of the results
        rho = spearmanr([q[k] for q in rows], [q[output] for q in rows])[0]
        assert float(r["spearman"]) == pytest.approx(rho, rel=1e-9)
    # the damper force's RMS follows the hard setting (the force the skyhook switches to)
    assert float(by[("ride f_d_rms", "controller.c_hard")]["spearman"]) > 0.8
    doc = json.loads((out / "sweep.json").read_text())
    assert doc["design"]["method"] == "lhs" and doc["design"]["sensitivity"] == \
        "sensitivity.json"
    # the sweep report shows the table (every output x parameter) and the scatter plots
    from orchestrator.report.cli import render
    from orchestrator.report.markup import fmt

    kind, html = render(out)
    assert kind == "sweep" and 'id="sensitivity"' in html and "Latin hypercube" in html
    for r in sens["rows"]:
        assert fmt(r["spearman"]) in html
    assert html.count("<td>controller.c_hard</td>") >= len(sens["outputs"])
