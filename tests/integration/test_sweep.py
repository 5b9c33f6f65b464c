"""``suscosim sweep``: real runs (real node processes over Zenoh on loopback), a killed run,
resume, bad sweep files; plus the pure helpers (point ids, TOML values, journal progress)."""

from __future__ import annotations

import csv
import json
import os
import signal
import time
import tomllib
from pathlib import Path

import pytest

from cosim.journal import last_step
from orchestrator.sweep import load_sweep, point_id, toml_value

from ..conftest import CH3_STEP, COARSE_ARM, ROOT, popen_suscosim, suscosim

GRID_2X2 = f"""
[sweep]
name = "t2x2"
base = "{CH3_STEP}"
jobs = 2
[sweep.grid]
"run.h" = [0.001, 0.002]
[sweep.grid.tyre]
pc = {{ tyre = {{ model = "point_contact", stiffness = 192000.0 }} }}
[sweep.grid.tyre.ffp]
tyre = {{ model = "fixed_footprint", stiffness = 192000.0, n = 4, contact_length = 0.2 }}
[sweep.set]
"run.t_end" = 0.6
"run.stall_timeout_s" = 30.0  # a shared 2-core machine can starve a node for > 5 s
"""


def _write(tmp_path: Path, name: str, text: str) -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def _procs_with(*needles: str) -> list[int]:
    """PIDs whose command line contains every needle (read from /proc, no pgrep)."""
    out = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            cmd = (d / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if all(n in cmd for n in needles):
            out.append(int(d.name))
    return out


# ------------------------------------------------------------------ pure helpers

def test_toml_value_round_trips_through_tomllib():
    values = [0.001, 1e-05, -3, True, "tss1", 'a "q" \\ é', [1, 2.5, "x"],
              {"law": "passive", "c": 3800.0, "damper": {"motion_ratio": 0.628}},
              float("inf")]
    for v in values:
        assert tomllib.loads(f"v = {toml_value(v)}")["v"] == v


def test_point_ids_are_deterministic_valid_and_short():
    a = point_id("ch6", ["pave", "tss1", 0.0005])
    assert a == "ch6-pave-tss1-0.0005" == point_id("ch6", ["pave", "tss1", 0.0005])
    long = point_id("s" * 40, ["x" * 30, "y" * 30])
    assert len(long) <= 64 and long != point_id("s" * 40, ["x" * 30, "y" * 31])
    assert point_id("s", ["a b/c"]) == "s-a_b_c"


def test_grid_product_variants_and_overrides(tmp_path):
    sweep = load_sweep(_write(tmp_path, "g.toml", GRID_2X2))
    assert [p.id for p in sweep.points] == ["t2x2-0.001-pc", "t2x2-0.001-ffp",
                                            "t2x2-0.002-pc", "t2x2-0.002-ffp"]
    p = sweep.points[1]
    assert p.params == {"run.h": 0.001, "tyre": "ffp"}
    assert p.overrides["run.t_end"] == 0.6 and p.overrides["tyre"]["model"] == "fixed_footprint"
    # the run id: the point id and this invocation's random part (#15 item 3); the
    # fingerprint (resume) is computed with the point id alone, the same in every invocation
    from orchestrator.sweep.serve import point_of_run
    from orchestrator.sweep.spec import INVOCATION

    assert p.run_id == f"t2x2-0.001-ffp-{INVOCATION}" and len(INVOCATION) == 6
    assert p.set_args[-1] == f'run.id="{p.run_id}"'
    assert p.fingerprint_args[-1] == 'run.id="t2x2-0.001-ffp"'
    ids = [q.id for q in sweep.points]
    assert point_of_run(p.run_id, ids) == p.id and point_of_run(p.id, ids) == p.id
    assert point_of_run("t2x2-0.001-ffp-zz", ids) is None  # not a token
    assert point_of_run("t2x2-0.001-ffp-abc123", ids) == p.id  # another invocation's run
    assert point_of_run("someone-else", ids) is None


def test_last_step_reads_the_journal_tail(tmp_path):
    from cosim.journal import JournalWriter
    from cosim.wire import encode

    assert last_step(tmp_path / "missing.msgpack") is None
    w = JournalWriter(tmp_path / "j.msgpack", "r")
    for k in range(3000):
        w.append("plant/state", encode("data", k, k * 1e-3, {"z_b": 0.1 * k, "blob": b"\x93" * 7}))
    w.close()
    assert last_step(tmp_path / "j.msgpack") == 2999
    with open(tmp_path / "j.msgpack", "ab") as fh:  # a torn last record
        fh.write(b"\x93\xabplant/state\xc4\x40partial")
    assert last_step(tmp_path / "j.msgpack") == 2999


# ------------------------------------------------------------------ bad sweep files

@pytest.mark.integration
def test_bad_sweep_files_exit_2_naming_the_key(tmp_path):
    out = tmp_path / "out"
    bad_key = _write(tmp_path, "k.toml", GRID_2X2.replace("jobs = 2", "jbos = 2"))
    res = suscosim("sweep", str(bad_key), "--out", str(out))
    assert res.returncode == 2 and "sweep.jbos" in res.stderr, res.stderr
    assert "did you mean 'jobs'" in res.stderr, res.stderr  # read with cosim's ConfigReader
    assert "Traceback" not in res.stderr
    bad_scenario_key = _write(tmp_path, "s.toml", GRID_2X2.replace('"run.t_end" = 0.6',
                                                                  '"road.sped_kmh" = 40.0'))
    res = suscosim("sweep", str(bad_scenario_key), "--out", str(out))
    assert res.returncode == 2 and "road.sped_kmh" in res.stderr, res.stderr
    assert "t2x2-0.001-pc" in res.stderr  # the point is named
    bad_value = _write(tmp_path, "v.toml", GRID_2X2.replace("[0.001, 0.002]", "[0.001, -1.0]"))
    res = suscosim("sweep", str(bad_value), "--out", str(out))
    assert res.returncode == 2 and "run.h" in res.stderr, res.stderr
    missing_base = _write(tmp_path, "b.toml", GRID_2X2.replace(str(CH3_STEP), "nope.toml"))
    res = suscosim("sweep", str(missing_base), "--out", str(out))
    assert res.returncode == 2 and "nope.toml" in res.stderr, res.stderr
    assert not (out / "runs").exists()  # nothing was started


# ------------------------------------------------------------------ real sweeps

@pytest.mark.integration
def test_sweep_2x2_results_then_resume_redoes_nothing(tmp_path):
    f = _write(tmp_path, "g.toml", GRID_2X2)
    out = tmp_path / "sw"
    res = suscosim("sweep", str(f), "--out", str(out), timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    with open(out / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 4
    assert {(r["run.h"], r["tyre"]) for r in rows} == {("0.001", "pc"), ("0.001", "ffp"),
                                                       ("0.002", "pc"), ("0.002", "ffp")}
    assert all(r["status"] == "ok" and float(r["steps_per_s"]) > 0 for r in rows)
    # the tyre model really changed: the fixed footprint's peak tyre force is lower
    peak = {(r["run.h"], r["tyre"]): float(r["tyre_road/force/F_t peak"]) for r in rows}
    assert peak[("0.001", "ffp")] < peak[("0.001", "pc")]
    doc = json.loads((out / "sweep.json").read_text())
    assert doc["name"] == "t2x2" and doc["grid"] == {"run.h": [0.001, 0.002],
                                                     "tyre": ["pc", "ffp"]}
    assert doc["set"] == {"run.t_end": 0.6, "run.stall_timeout_s": 30.0}
    for p in doc["points"]:
        summary = json.loads((out / p["run_dir"] / "summary.json").read_text())
        assert summary["status"] == "ok" and summary["run_id"].startswith(p["id"] + "-")
        assert summary["h"] == p["params"]["run.h"] and summary["n_steps"] == round(
            0.6 / p["params"]["run.h"])
    assert len(json.loads((out / "results.json").read_text())) == 4
    mtimes = {p: p.stat().st_mtime_ns for p in out.glob("runs/*/summary.json")}
    res = suscosim("sweep", str(f), "--out", str(out), timeout=120)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "0 to run (4 already done)" in res.stdout
    assert {p: p.stat().st_mtime_ns for p in out.glob("runs/*/summary.json")} == mtimes
    assert "t2x2-0.002-ffp" in res.stdout  # the table lists every point again
    # two invocations of one sweep: different run ids (never the same id on one router)
    ids = {json.loads(q.read_text())["run_id"] for q in out.glob("runs/*/summary.json")}
    assert len(ids) == 4


KILL_SWEEP = f"""
[sweep]
name = "tkill"
base = "{CH3_STEP}"
jobs = 2
[sweep.grid]
"run.t_end" = [0.5, 2.0]
[sweep.set]
"run.stall_timeout_s" = 30.0
"""


@pytest.mark.integration
def test_killed_run_fails_alone_and_resume_redoes_only_it(tmp_path):
    f = _write(tmp_path, "k.toml", KILL_SWEEP)
    out = tmp_path / "sw"
    victim = "tkill-2.0"
    proc = popen_suscosim("sweep", str(f), "--out", str(out))
    try:
        deadline = time.monotonic() + 120
        pids: list[int] = []
        while time.monotonic() < deadline:  # the victim's run is stepping: kill it
            pids = _procs_with("orchestrator", " run ", f"runs/{victim} ")
            k = last_step(out / "runs" / victim / "journal.msgpack")
            if pids and k is not None and k > 100:
                break
            time.sleep(0.1)
        assert pids, "the victim's run process never appeared"
        os.kill(pids[0], signal.SIGKILL)
        stdout, stderr = proc.communicate(timeout=180)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 1, stdout + stderr
    rows = {r["point"]: r for r in json.loads((out / "results.json").read_text())}
    assert rows["tkill-0.5"]["status"] == "ok"
    assert rows[victim]["status"] == "failed" and "SIGKILL" in rows[victim]["error"]
    # the killed run's node processes were cleaned up (same process group)
    deadline = time.monotonic() + 15
    while _procs_with("orchestrator", "node", f"--run {victim}") and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not _procs_with("orchestrator", "node", f"--run {victim}")
    ok_summary = out / "runs" / "tkill-0.5" / "summary.json"
    mtime = ok_summary.stat().st_mtime_ns
    res = suscosim("sweep", str(f), "--out", str(out), timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "1 to run (1 already done)" in res.stdout
    assert ok_summary.stat().st_mtime_ns == mtime
    summary = json.loads((out / "runs" / victim / "summary.json").read_text())
    assert summary["status"] == "ok" and summary["n_steps"] == 2000


FATIGUE_SWEEP = f"""
[sweep]
name = "tfat"
base = "{ROOT / 'scenarios' / 'ch4_qvm_realistic_bump_pothole.toml'}"
fatigue = true
[sweep.grid]
"road.speed_kmh" = [34.0]
[sweep.set]
"run.t_end" = 0.4
"run.stall_timeout_s" = 30.0
"fatigue.influence" = "{COARSE_ARM}"
"""


@pytest.mark.integration
def test_sweep_with_fatigue_on_a_short_realistic_run(tmp_path):
    f = _write(tmp_path, "f.toml", FATIGUE_SWEEP)
    out = tmp_path / "sw"
    res = suscosim("sweep", str(f), "--out", str(out), timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    (row,) = json.loads((out / "results.json").read_text())
    fat = json.loads((out / "runs" / row["point"] / "fatigue" / "summary.json").read_text())
    assert row["life_km"] == fat["min_life_km"] and row["critical_node"] == fat[
        "critical_node_id"]
    assert row["max_damage"] > 0
    for name in ("damage_per_node.csv", "damage_map.png"):
        assert (out / "runs" / row["point"] / "fatigue" / name).is_file()
    # without fatigue results the point is not done: only the fatigue is redone
    run_summary = out / "runs" / row["point"] / "summary.json"
    mtime = run_summary.stat().st_mtime_ns
    (out / "runs" / row["point"] / "fatigue" / "summary.json").unlink()
    res = suscosim("sweep", str(f), "--out", str(out), timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    assert run_summary.stat().st_mtime_ns == mtime
    assert (out / "runs" / row["point"] / "fatigue" / "summary.json").is_file()


SERVE_SWEEP = f"""
[sweep]
name = "tserve"
base = "{CH3_STEP}"
jobs = 2
[sweep.grid]
"run.h" = [0.001, 0.002]
[sweep.set]
"run.t_end" = 0.4
"run.stall_timeout_s" = 30.0
"""


@pytest.mark.integration
def test_sweep_through_a_router_with_the_plant_served_elsewhere(tmp_path, monkeypatch):
    """The multi-machine recipe of docs/sweeps.md on loopback: a router, a 'remote' side that
    serves the plant node for every point, and the sweep with --external plant (both sides
    given the same secret, SUSCOSIM_KEY, as the messages of a run are signed)."""
    import secrets

    from cosim.bus import free_loopback_endpoint

    monkeypatch.delenv("SUSCOSIM_KEY_FILE", raising=False)
    monkeypatch.delenv("SUSCOSIM_KEY", raising=False)
    f = _write(tmp_path, "s.toml", SERVE_SWEEP)
    res = suscosim("sweep", str(f), "--serve", "plant", "--connect", "tcp/127.0.0.1:9",
                   "--out", str(tmp_path / "remote"))
    assert res.returncode == 2 and "SUSCOSIM_KEY" in res.stderr, res.stdout + res.stderr
    monkeypatch.setenv("SUSCOSIM_KEY", secrets.token_hex(16))  # inherited by both sides
    ep = free_loopback_endpoint()
    router = popen_suscosim("router", "--listen", ep)
    server = None
    try:
        time.sleep(1.0)
        assert router.poll() is None, router.stderr.read()
        server = popen_suscosim("sweep", str(f), "--serve", "plant", "--connect", ep,
                                "--out", str(tmp_path / "remote"))
        res = suscosim("sweep", str(f), "--out", str(tmp_path / "sw"), "--connect", ep,
                       "--external", "plant", timeout=300)
        assert res.returncode == 0, res.stdout + res.stderr
        out, err = server.communicate(timeout=60)  # it ends once every point was served
        assert server.returncode == 0, out + err
        for pid in ("tserve-0.001", "tserve-0.002"):
            summary = json.loads((tmp_path / "sw" / "runs" / pid / "summary.json").read_text())
            assert summary["status"] == "ok"
            assert not (tmp_path / "sw" / "runs" / pid / "logs" / "plant.log").exists()
            assert (tmp_path / "remote" / "serve" / f"{pid}.plant.log").is_file()
            assert f"{pid}: done" in out
    finally:
        for p in (server, router):
            if p is not None and p.poll() is None:
                p.send_signal(signal.SIGTERM)
                try:
                    p.wait(timeout=10)
                except Exception:
                    p.kill()
