"""``suscosim sweep --executor dask``: a real ``distributed`` scheduler and two worker
processes on loopback (``suscosim cluster``); every point is a real run (node processes over
Zenoh on the worker). Both workers run points, the results equal the local executor's, a
worker killed mid-run has its point rerun on the other, an interrupted sweep resumes; and
(root) scheduler and worker in different network namespaces."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from ..conftest import CH3_STEP, ROOT, popen_suscosim, suscosim

distributed = pytest.importorskip("distributed", reason="needs dask[distributed] (pyproject)")

pytestmark = pytest.mark.integration

SWEEP = f"""
[sweep]
name = "tdask"
base = "{CH3_STEP}"
jobs = 2
[sweep.grid]
"controller.c" = [1000.0, 1500.0, 2000.0, 2500.0]
[sweep.set]
"run.t_end" = T_END
"road.t_start" = 0.1
"run.stall_timeout_s" = 30.0
"""
STATS = ("peak", "rms")


def _write(tmp_path: Path, t_end: float) -> Path:
    f = tmp_path / "s.toml"
    f.write_text(SWEEP.replace("T_END", repr(t_end)))
    return f


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _workers(address: str, n: int, timeout_s: float = 60.0) -> dict:
    """The scheduler's worker table once ``n`` workers have joined (+ each one's pid)."""
    with distributed.Client(address, timeout="20s") as c:
        c.wait_for_workers(n, timeout=timeout_s)
        workers = c.scheduler_info(n_workers=-1)["workers"]
        for addr, pid in c.run(os.getpid).items():
            workers[addr]["pid"] = pid
        return workers


def _cluster():
    """``suscosim cluster --workers 2 --no-nanny`` on a free loopback port."""
    port = _free_port()
    proc = popen_suscosim("cluster", "--workers", "2", "--no-nanny", "--port", str(port))
    address = f"tcp://127.0.0.1:{port}"
    try:
        _workers(address, 2)
        yield address
    finally:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()


@pytest.fixture(scope="module")
def cluster():
    """One cluster for the tests that leave its workers alive."""
    yield from _cluster()


@pytest.fixture
def own_cluster():
    """A cluster of its own, for a test that kills a worker."""
    yield from _cluster()


def _rows(out: Path) -> dict[str, dict]:
    return {r["point"]: r for r in json.loads((out / "results.json").read_text())}


def _point_worker(out: Path, pid: str) -> dict:
    return json.loads((out / "runs" / pid / "point.json").read_text())["worker"]


def _executing(dask_worker) -> list[str]:
    """(Run on each worker by ``Client.run``) the keys of the tasks it is executing."""
    return [str(k) for k, ts in dask_worker.state.tasks.items() if ts.state == "executing"]


def _cmdlines_with(needle: str, pid: bool = False) -> list[str]:
    """Command lines of the processes whose command line holds ``needle`` (``pid``: each
    prefixed by its process id)."""
    out = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                cmd = (d / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
            except OSError:
                continue
            if needle in cmd:
                out.append(f"{d.name} {cmd}" if pid else cmd)
    return out


def test_dask_sweep_uses_both_workers_and_equals_the_local_executor(tmp_path, cluster):
    f = _write(tmp_path, 0.4)
    res = suscosim("sweep", str(f), "--out", str(tmp_path / "local"), timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    res = suscosim("sweep", str(f), "--out", str(tmp_path / "dask"), "--executor", "dask",
                   "--scheduler", cluster, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "2 Dask workers" in res.stdout
    local, dask = _rows(tmp_path / "local"), _rows(tmp_path / "dask")
    assert local.keys() == dask.keys() and len(dask) == 4
    workers = set()
    for pid, row in dask.items():
        assert row["status"] == "ok", row
        w = _point_worker(tmp_path / "dask", pid)
        assert w["executor"] == "dask" and w["address"].startswith("tcp://127.0.0.1:")
        assert row["worker"] == w["name"]
        workers.add(w["name"])
        # the same run: every channel statistic and the recorded table, to the bit
        for col, v in local[pid].items():
            if col.endswith(STATS):
                assert row[col] == v, (pid, col)
        assert (tmp_path / "dask" / "runs" / pid / "table.csv").read_bytes() == (
            tmp_path / "local" / "runs" / pid / "table.csv").read_bytes()
        summary = json.loads((tmp_path / "dask" / "runs" / pid / "summary.json").read_text())
        assert summary["run_id"].startswith(pid + "-") and summary["n_steps"] == 400
    assert workers == {"w0", "w1"}  # both workers ran points


def test_interrupted_dask_sweep_resumes_and_a_killed_workers_point_reruns(tmp_path,
                                                                        own_cluster):
    cluster = own_cluster
    f = _write(tmp_path, 1.0)
    out = tmp_path / "sw"
    args = ("sweep", str(f), "--out", str(out), "--executor", "dask", "--scheduler", cluster)
    # 1. interrupt the sweep once a point has come back
    proc = popen_suscosim(*args)
    try:
        deadline = time.monotonic() + 180
        while time.monotonic() < deadline and not list(out.glob("runs/*/summary.json")):
            assert proc.poll() is None, proc.communicate()
            time.sleep(0.2)
        proc.send_signal(signal.SIGTERM)
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, stdout + stderr
    done = {p.parent.name: p.stat().st_mtime_ns for p in out.glob("runs/*/summary.json")}
    assert 1 <= len(done) < 4
    # 2. resume; kill the worker that runs a point, mid-run
    workers = _workers(cluster, 2)
    proc = popen_suscosim(*args)
    killed_point = victim = None
    try:
        deadline = time.monotonic() + 120
        with distributed.Client(cluster, timeout="20s") as c:
            while time.monotonic() < deadline and killed_point is None:
                executing = c.run(_executing)
                busy = [(a, k) for a, ks in executing.items() for k in ks]
                if busy:
                    time.sleep(1.5)  # its run is stepping
                    addr, key = busy[0]
                    if key in c.run(_executing).get(addr, []):
                        victim = workers[addr]
                        killed_point = str(key)[len("suscosim-"):-9]
                        os.kill(victim["pid"], signal.SIGKILL)
                time.sleep(0.1)
        assert killed_point is not None and victim is not None, "no worker ran a point"
        stdout, stderr = proc.communicate(timeout=300)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, stdout + stderr
    assert f"{4 - len(done)} to run ({len(done)} already done)" in stdout
    rows = _rows(out)
    assert all(r["status"] == "ok" for r in rows.values()), rows
    assert killed_point in rows and killed_point not in done
    other = ({"w0", "w1"} - {victim["name"]}).pop()
    assert _point_worker(out, killed_point)["name"] == other  # rerun elsewhere
    assert f"{killed_point}: started again on worker {other}" in stderr
    assert {p: m for p, m in ((q, (out / "runs" / q / "summary.json").stat().st_mtime_ns)
                              for q in done)} == done  # finished points were not redone
    # the killed worker's run died with it (no orphaned run in its scratch folder)
    deadline = time.monotonic() + 20
    while _cmdlines_with(victim["local_directory"]) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not _cmdlines_with(victim["local_directory"])


def test_a_failed_point_is_reported_and_the_others_go_on(tmp_path, cluster):
    """The run of one point is SIGKILLed on its worker: that point is failed (a result, not a
    Dask retry), the other finishes, exit 1; a rerun redoes only the failed one."""
    f = tmp_path / "s.toml"
    f.write_text(SWEEP.replace("T_END", "0.4").replace(
        '"controller.c" = [1000.0, 1500.0, 2000.0, 2500.0]',
        '"run.t_end" = [0.4, 2.5]').replace('"run.t_end" = 0.4\n', ""))
    out = tmp_path / "sw"
    victim = "tdask-2.5"
    args = ("sweep", str(f), "--out", str(out), "--executor", "dask", "--scheduler", cluster)
    proc = popen_suscosim(*args)
    try:
        deadline = time.monotonic() + 120
        pids: list[int] = []
        while time.monotonic() < deadline and not pids:
            pids = [int(c.split()[0]) for c in _cmdlines_with(f"/{victim}.toml", pid=True)
                    if " run " in c]
            time.sleep(0.2)
        assert pids, "the victim's run never started"
        time.sleep(1.5)
        os.kill(pids[0], signal.SIGKILL)
        stdout, stderr = proc.communicate(timeout=180)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 1, stdout + stderr
    rows = _rows(out)
    assert rows["tdask-0.4"]["status"] == "ok"
    assert rows[victim]["status"] == "failed" and "SIGKILL" in rows[victim]["error"]
    res = suscosim(*args, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "1 to run (1 already done)" in res.stdout


FATIGUE = f"""
[sweep]
name = "tdfat"
base = "{ROOT / 'scenarios' / 'ch4_qvm_realistic_bump_pothole.toml'}"
fatigue = true
runs_dir = "shared/runs"
[sweep.grid]
"road.speed_kmh" = [34.0]
[sweep.set]
"run.t_end" = 0.4
"run.stall_timeout_s" = 30.0
"""


def test_dask_fatigue_in_a_shared_runs_dir_and_a_fatigue_only_rerun(tmp_path, cluster):
    """The workers write the run folder in place under --runs-dir (a shared folder; with
    --out the sweep file's runs_dir is not used, #46); a point whose fatigue results are
    missing gets only its fatigue, on a worker."""
    f = tmp_path / "f.toml"
    f.write_text(FATIGUE)
    out = tmp_path / "sw"
    args = ("sweep", str(f), "--out", str(out), "--runs-dir", str(tmp_path / "shared" / "runs"),
            "--executor", "dask", "--scheduler", cluster)
    res = suscosim(*args, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    (row,) = json.loads((out / "results.json").read_text())
    run_dir = tmp_path / "shared" / "runs" / row["point"]
    assert row["run_dir"] == str(run_dir) and not (out / "runs").exists()
    fat = json.loads((run_dir / "fatigue" / "summary.json").read_text())
    assert row["life_km"] == fat["min_life_km"] and row["max_damage"] > 0
    summary = run_dir / "summary.json"
    mtime = summary.stat().st_mtime_ns
    (run_dir / "fatigue" / "summary.json").unlink()
    res = suscosim(*args, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    assert summary.stat().st_mtime_ns == mtime  # the run was not redone
    again = json.loads((run_dir / "fatigue" / "summary.json").read_text())
    assert again.pop("source") == "batch" and fat.pop("source") == "live"  # node, then worker
    # the batch adds what only it computes (both S-N methods, pseudo-damage, the extra
    # output files); everything the live node wrote is the same but its screening: the live
    # node screens by default (fatigue.screen, docs/live_fatigue.md), the batch never, and
    # the lives, critical node and ten most damaged nodes are the same either way
    live_screen, batch_screen = fat.pop("screening"), again.pop("screening")
    assert live_screen["fraction"] == 0.1 and live_screen["screened_nodes"] > 0
    assert batch_screen["note"] == "off" and batch_screen["screened_nodes"] == 0
    assert set(fat) <= set(again)
    assert {k: again[k] for k in fat} == fat
    meta = json.loads((run_dir / "point.json").read_text())
    assert meta["fatigue_worker"]["executor"] == "dask"


def test_dask_executor_bad_arguments_exit_2(tmp_path):
    f = _write(tmp_path, 0.4)
    res = suscosim("sweep", str(f), "--executor", "dask", "--out", str(tmp_path / "o"))
    assert res.returncode == 2 and "--scheduler" in res.stderr, res.stderr
    res = suscosim("sweep", str(f), "--executor", "dask", "--scheduler", "tcp://127.0.0.1:1",
                   "--external", "plant", "--out", str(tmp_path / "o"))
    assert res.returncode == 2 and "local executor" in res.stderr, res.stderr
    assert "Traceback" not in res.stderr
    res = suscosim("sweep", str(f), "--executor", "dask", "--scheduler", "tcp:/x:y",
                   "--out", str(tmp_path / "o"))
    assert res.returncode == 2 and "'tcp:/x:y'" in res.stderr, res.stderr
    res = suscosim("cluster", "--workers", "0")
    assert res.returncode == 2 and "--workers" in res.stderr, res.stderr


# ------------------------------------------------------------------ network namespaces

@pytest.mark.netns
@pytest.mark.long
def test_scheduler_and_worker_in_different_namespaces(tmp_path):
    """Scheduler in namespace A, one worker in B, the sweep in C (the topology of
    tests/integration/netns.py: B and C reach each other only through A's two links)."""
    from .netns import ADDR, MAIN, PLANT, ROUTER, ROUTER_ADDR, Topology, unavailable

    reason = unavailable()
    if reason:
        pytest.skip(reason)
    t = Topology()
    env = dict(os.environ, PYTHONPATH=str(ROOT), PYTHONUNBUFFERED="1")
    procs = []
    try:
        py = sys.executable
        procs.append(subprocess.Popen(t.cmd(ROUTER, [
            py, "-m", "distributed.cli.dask_scheduler", "--host", "0.0.0.0", "--port", "8786",
            "--no-dashboard"]), env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        time.sleep(2.0)
        procs.append(subprocess.Popen(t.cmd(PLANT, [
            py, "-m", "distributed.cli.dask_worker", f"tcp://{ROUTER_ADDR[PLANT]}:8786",
            "--host", ADDR[PLANT], "--nthreads", "1", "--no-nanny", "--name", "nsB",
            "--no-dashboard"]), env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        f = tmp_path / "s.toml"
        f.write_text(SWEEP.replace("T_END", "0.4").replace(
            "[1000.0, 1500.0, 2000.0, 2500.0]", "[1000.0, 2000.0]"))
        out = tmp_path / "sw"
        res = subprocess.run(t.cmd(MAIN, [
            py, "-m", "orchestrator", "sweep", str(f), "--out", str(out), "--executor",
            "dask", "--scheduler", f"tcp://{ROUTER_ADDR[MAIN]}:8786"]), env=env, cwd=ROOT,
            capture_output=True, text=True, timeout=300)
        assert res.returncode == 0, res.stdout + res.stderr
        rows = _rows(out)
        assert len(rows) == 2 and all(r["status"] == "ok" for r in rows.values()), rows
        for pid in rows:
            w = _point_worker(out, pid)
            assert w["name"] == "nsB" and w["address"].startswith(f"tcp://{ADDR[PLANT]}:")
            assert (out / "runs" / pid / "table.parquet").is_file()
    finally:
        for p in procs:
            p.send_signal(signal.SIGTERM)
        for p in procs:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
        t.close()
