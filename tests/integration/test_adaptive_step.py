"""The adaptive communication step (``run.h = "auto"``, issue #29 item 3), through real runs:
on the bump + pothole it reaches a fixed step's accuracy (against the reference solution) in
fewer steps; distributed runs (real node processes on Zenoh) end exactly at t_end, the live
fatigue node and the report take the non-uniform time base; what it cannot do is refused."""

from __future__ import annotations

import json

import numpy as np
import pytest

from cosim import scenario as sc
from cosim.errors import ScenarioError
from cosim.table import read_table
from orchestrator.accuracy import peak_errors, worst
from orchestrator.runner import resolve

from ..conftest import ROOT, suscosim

CH3 = ROOT / "scenarios" / "ch3_step_quarter_car.toml"
CH6 = ROOT / "scenarios" / "thesis" / "ch6_realistic_qvm.toml"
BUMP_POTHOLE = ('road={type="events", speed_kmh=34.0, length_m=15.0, events=['
                '{type="bump", height=0.05, length=1.0, x_start=3.0}, '
                '{type="pothole", depth=0.04, length=0.6, x_start=10.0, shape="cosine"}]}')
BASE = ("--set", BUMP_POTHOLE, "--set", "run.t_end=0", "--set", 'run.coupling="hold"',
        "--quiet")
AUTO = ("--set", 'run.h="auto"', "--set", "run.h_tol=0.003")


def _run(out, *args, timeout=300.0):
    r = suscosim("run", *args, "--out", str(out), timeout=timeout)
    assert r.returncode == 0, r.stdout + r.stderr
    return json.loads((out / "summary.json").read_text())


@pytest.fixture(scope="module")
def bump(tmp_path_factory):
    root = tmp_path_factory.mktemp("adaptive")
    _run(root / "ref", str(CH3), *BASE, "--mode", "reference", "--set", "run.h=0.00025")
    return root


def test_adaptive_step_matches_a_fixed_step_in_fewer_steps(bump):
    ref = read_table(bump / "ref" / "table.parquet")
    fixed = _run(bump / "fixed", str(CH3), *BASE, "--mode", "monolithic",
                 "--set", "run.h=0.00025")
    auto = _run(bump / "auto", str(CH3), *BASE, *AUTO, "--mode", "monolithic")
    e_fixed = worst(peak_errors(read_table(bump / "fixed" / "table.parquet"), ref))
    e_auto = worst(peak_errors(read_table(bump / "auto" / "table.parquet"), ref))
    print(f"fixed 0.25 ms: {fixed['n_steps']} steps, {e_fixed:.3f} %; "
          f"auto: {auto['n_steps']} steps, {e_auto:.3f} %")
    assert e_auto <= e_fixed and auto["n_steps"] < 0.75 * fixed["n_steps"]
    a = auto["adaptive_step"]
    assert a["steps"] == auto["n_steps"] and a["h_largest"] > 10 * a["h_smallest"]
    # a fixed step of the adaptive run's mean is worse: the step went where it was needed
    mean = _run(bump / "mean", str(CH3), *BASE, "--mode", "monolithic",
                "--set", f"run.h={a['h_mean']:.6g}")
    e_mean = worst(peak_errors(read_table(bump / "mean" / "table.parquet"), ref))
    assert e_mean > 1.5 * e_auto, (e_mean, e_auto)
    assert mean["n_steps"] <= auto["n_steps"] + 2


def test_distributed_adaptive_run_ends_at_t_end_and_is_the_monolithic_one(bump):
    s = _run(bump / "dist", str(CH3), *BASE, *AUTO)
    t = read_table(bump / "dist" / "table.parquet")["t"]
    assert t[-1] == pytest.approx(s["t_end"], abs=1e-12) and np.all(np.diff(t) > 0)
    assert s["n_steps"] == len(t) - 1 and s["status"] == "ok"
    # the same steps and values as the monolithic run (the same node code on another bus)
    mono = bump / "auto" / "table.parquet"
    if not mono.exists():
        _run(bump / "auto", str(CH3), *BASE, *AUTO, "--mode", "monolithic")
    assert (bump / "dist" / "table.parquet").read_bytes() == mono.read_bytes()
    r = suscosim("report", str(bump / "dist"), "--out", str(bump / "dist" / "r.html"))
    assert r.returncode == 0, r.stderr
    html = (bump / "dist" / "r.html").read_text()
    assert "resampled linearly to h_min" in html and "not uniformly sampled" not in html
    r = suscosim("ride", str(bump / "dist"))
    assert r.returncode == 0 and "resampled" in r.stderr, r.stderr


def test_the_realistic_corner_with_live_fatigue_takes_an_adaptive_step(tmp_path):
    s = _run(tmp_path / "c", str(CH6), "--set", "road.length_m=5", "--quiet", *AUTO,
             "--set", "run.h_max=0.002")
    assert s["status"] == "ok" and s["fatigue"]["min_life_km"] != "inf"
    assert (tmp_path / "c" / "fatigue" / "damage_per_node.csv").is_file()
    assert s["adaptive_step"]["steps"] == s["n_steps"]


@pytest.mark.parametrize("sets, key", [
    (('run.exchange="parallel"',), "run.exchange"),
    (("run.checkpoint_every_s=0.5",), "run.checkpoint_every_s"),
    (('controller={law="tss3", I_soft=0.0, I_hard=0.6}',), "run.h"),
    (("run.h_max=0.00005",), "run.h_max"),
])
def test_what_an_adaptive_step_cannot_do_is_refused(sets, key):
    """The preflight of ``run`` (:func:`orchestrator.runner.resolve`, in-process: the CLI's
    exit 2 for a ScenarioError is tested with the other bad scenarios)."""
    with pytest.raises(ScenarioError) as e:
        resolve(sc.load(CH3, ['run.h="auto"', *sets]))
    assert e.value.key == key and e.value.exit_code == 2


def test_the_magic_formula_tyre_is_refused_with_an_adaptive_step():
    with pytest.raises(ScenarioError, match="magic_formula"):
        resolve(sc.load(ROOT / "scenarios" / "events" / "braking_50kmh_0p8g.toml",
                        ['run.h="auto"']))
    r = suscosim("check", str(CH3), "--set", 'run.h="auto"', "--set", 'run.exchange="parallel"')
    assert r.returncode == 2 and "run.exchange" in r.stderr and "Traceback" not in r.stderr
