"""Checkpoints, resume and fork of whole runs (issue #29 items 4-5), with real node processes
on real Zenoh sessions (the one-process engine, orchestrator/inprocess.py, has no checkpoints).

Bit for bit means ``cmp``: the resumed run's ``table.parquet``, ``table.csv`` and the live
fatigue node's files are the uninterrupted run's bytes.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from ..conftest import COARSE_ARM, ROOT, node_pids, popen_suscosim, suscosim

CH3 = ROOT / "scenarios" / "ch3_step_quarter_car.toml"
CH6 = ROOT / "scenarios" / "thesis" / "ch6_realistic_qvm.toml"
FILES = ("table.parquet", "table.csv")
FATIGUE_FILES = ("fatigue/damage_per_node.csv", "fatigue/summary.json")


def _ok(*args: str, timeout: float = 300.0) -> str:
    r = suscosim(*args, timeout=timeout)
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout + r.stderr


def _same(a: Path, b: Path, files=FILES) -> None:
    for f in files:
        assert (a / f).read_bytes() == (b / f).read_bytes(), f"{f} differs"


def _manifests(run_dir: Path) -> list[int]:
    found = (run_dir / "checkpoints").glob("k*/manifest.json")
    return sorted(int(p.parent.name[1:]) for p in found)


@pytest.fixture(scope="module")
def ch3_parallel(tmp_path_factory) -> tuple[Path, Path]:
    """A Ch 3 run (parallel exchange: the lagged state crosses the boundary) with
    checkpoints every 1 s, and the same run without checkpoints."""
    root = tmp_path_factory.mktemp("ckpt")
    common = ("--mode", "distributed", "--quiet", "--set", 'run.exchange="parallel"')
    _ok("run", str(CH3), "--out", str(root / "plain"), *common)
    _ok("run", str(CH3), "--out", str(root / "ckpt"), *common,
        "--set", "run.checkpoint_every_s=1.0")
    return root / "ckpt", root / "plain"


def test_checkpoints_do_not_change_the_run_and_are_complete(ch3_parallel):
    ckpt, plain = ch3_parallel
    _same(ckpt, plain)
    assert _manifests(ckpt) == [2000, 3000]  # run.checkpoint_keep = 2: the oldest pruned
    assert not (ckpt / "checkpoints" / "k001000").exists()
    doc = json.loads((ckpt / "checkpoints" / "k002000" / "manifest.json").read_text())
    assert doc["t"] == pytest.approx(2.0)
    assert sorted(doc["nodes"]) == ["controller", "plant", "recorder", "tyre_road"]


def test_resume_from_an_earlier_checkpoint_equals_the_uninterrupted_run(ch3_parallel, tmp_path):
    ckpt, _ = ch3_parallel
    run = tmp_path / "run"
    shutil.copytree(ckpt, run)
    (run / "checkpoints" / "k003000" / "manifest.json").unlink()  # as if killed before 3 s
    for f in FILES:
        (run / f).unlink()
    out = _ok("run", "--resume", str(run), "--quiet")
    assert "checkpoint at step 2000" in out
    _same(run, ckpt)
    assert (run / "checkpoints" / "journal-k002000.msgpack").is_file()  # the old one, aside
    summary = json.loads((run / "summary.json").read_text())
    assert summary["status"] == "ok"
    assert summary["resumed_from"] == {"k": 2000, "t": 2.0, "run_dir": str(run), "fork": False,
                                       "fresh": []}


def test_fork_with_the_same_settings_continues_the_parent_bit_for_bit(ch3_parallel, tmp_path):
    ckpt, _ = ch3_parallel
    out = _ok("run", "--fork", f"{ckpt}@2.0", "--out", str(tmp_path / "fork"), "--quiet")
    assert "changed: nothing" in out
    _same(tmp_path / "fork", ckpt)


@pytest.mark.parametrize("law", ['controller.c=3000.0',
                                 'controller={law="skyhook", c_sky=2500.0}'])
def test_fork_with_another_law_starts_from_the_parents_state(ch3_parallel, tmp_path, law):
    ckpt, _ = ch3_parallel
    out = _ok("run", "--fork", f"{ckpt}@2.0", "--out", str(tmp_path / "fork"), "--quiet",
              "--set", law)
    assert "starting afresh: controller" in out
    parent = pq.read_table(ckpt / "table.parquet").to_pandas()
    fork = pq.read_table(tmp_path / "fork" / "table.parquet").to_pandas()
    k = 2000
    assert len(fork) == len(parent)
    # every step before the fork is the parent's, and so is the state the fork starts from
    assert parent.iloc[:k].equals(fork.iloc[:k][parent.columns])
    state = [c for c in parent.columns if c.startswith("plant/state/")]
    assert parent.loc[k, state].equals(fork.loc[k, state])
    # the new law acts from its first step on (parallel: on the state of step k - 1)
    assert fork.loc[k, "controller/force/F_d"] != parent.loc[k, "controller/force/F_d"]
    assert (fork["plant/state/z_b"].iloc[-1] != parent["plant/state/z_b"].iloc[-1])
    # a field of the new law only (skyhook's c) is NaN in the parent's rows, set from k on
    for extra in set(fork.columns) - set(parent.columns):
        assert fork[extra].iloc[:k].isna().all() and fork[extra].iloc[k:].notna().all()


def test_bad_resumes_and_forks_are_refused_naming_why(ch3_parallel, tmp_path):
    """In-process where the CLI only passes the error on (its exit 2 checked twice)."""
    from cosim import scenario as sc
    from cosim.checkpoint import CheckpointError
    from cosim.errors import ScenarioError
    from orchestrator.resume import fork_scenario, resume_scenario
    from orchestrator.runner import resolve

    ckpt, plain = ch3_parallel
    r = suscosim("run", "--resume", str(plain))
    assert r.returncode == 2 and "no complete checkpoint" in r.stderr, r.stderr
    with pytest.raises(ScenarioError, match="road.height"):
        fork_scenario(f"{ckpt}@2.0", ["road.height=0.05"], str(tmp_path / "f"), resolve)
    with pytest.raises(CheckpointError, match="no checkpoint at t=1.5"):
        fork_scenario(f"{ckpt}@1.5", [], str(tmp_path / "g"), resolve)
    with pytest.raises(ScenarioError, match="a folder other than the parent"):
        fork_scenario(f"{ckpt}@2.0", [], str(ckpt), resolve)
    r = suscosim("run", "--resume", str(ckpt), "--set", "controller.c=1.0")
    assert r.returncode == 2 and "--fork" in r.stderr, r.stderr
    with pytest.raises(ScenarioError, match="whole number of steps"):
        resolve(sc.load(CH3, ["run.checkpoint_every_s=0.0015"]))
    damaged = tmp_path / "damaged"
    shutil.copytree(ckpt, damaged)
    node_file = damaged / "checkpoints" / "k003000" / "plant.ckpt"
    data = bytearray(node_file.read_bytes())
    data[-10] ^= 0xFF
    node_file.write_bytes(bytes(data))
    with pytest.raises(CheckpointError, match="plant.ckpt is damaged") as e:
        resume_scenario(damaged)
    assert e.value.exit_code == 2
    assert (damaged / "journal.msgpack").is_file()  # a refused resume moves nothing


def test_a_killed_distributed_run_resumes_bit_for_bit(tmp_path):
    """The realistic corner with the live fatigue node, distributed: the plant is killed
    (SIGKILL) after a checkpoint; ``--resume`` ends with the uninterrupted run's table and
    fatigue results, byte for byte."""
    common = ("--set", "road.length_m=10", "--quiet",  # ~2 100 steps of 0.5 ms
              "--set", f'fatigue.influence="{COARSE_ARM}"')  # it screens too: a light node
    ref, run = tmp_path / "ref", tmp_path / "run"
    _ok("run", str(CH6), "--out", str(ref), *common)
    proc = popen_suscosim("run", str(CH6), "--out", str(run), *common,
                          "--set", "run.checkpoint_every_s=0.25", "--set", 'run.id="ckkill"')
    try:
        deadline = time.monotonic() + 120
        while not any(k >= 1000 for k in _manifests(run)):
            assert time.monotonic() < deadline and proc.poll() is None, "no checkpoint"
            time.sleep(0.02)
        pids = node_pids("ckkill", "plant")
        assert pids, "plant process not found"
        for pid in pids:
            os.kill(pid, signal.SIGKILL)
        _, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 1 and "plant" in stderr, stderr
    last = _manifests(run)[-1]
    n_steps = json.loads((ref / "summary.json").read_text())["n_steps"]
    assert 1000 <= last < n_steps
    out = _ok("run", "--resume", str(run), "--quiet")
    assert f"checkpoint at step {last}" in out
    _same(run, ref, FILES + FATIGUE_FILES)
    summary = json.loads((run / "summary.json").read_text())
    assert summary["status"] == "ok"
    assert summary["fatigue"]["critical_node_id"] == json.loads(
        (ref / "summary.json").read_text())["fatigue"]["critical_node_id"]
