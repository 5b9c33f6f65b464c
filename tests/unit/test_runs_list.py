"""``suscosim runs``: run state from the files alone (fabricated run folders)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from cosim import run_folder
from cosim.journal import TAIL_BYTES, JournalWriter, last_step
from cosim.wire import encode
from orchestrator import runs

CHANNELS = ("plant/state", "tyre_road/force", "controller/force", "plant/response")


def _dead_pid() -> int:
    """The pid of a process that has exited (and been reaped)."""
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def _journal(folder: Path, run_id: str, last_k: int, lagging: int = 0) -> None:
    """Records of every channel for k = 0..last_k; the last channel stops ``lagging`` earlier."""
    import random

    rng = random.Random(k_seed := last_k)  # values zstd cannot shrink: a journal's real size
    w = JournalWriter(folder / "journal.msgpack", run_id)
    for k in range(last_k + 1):
        for i, name in enumerate(CHANNELS):
            if i == len(CHANNELS) - 1 and k > last_k - lagging:
                continue
            w.append(name, encode("data", k, k * 1e-3, {"x": float(k), "y": [1.0, 2.0],
                                                        "n": rng.random() + k_seed}))
        if k % 50 == 49:
            w.flush()  # a segment every 50 steps, as a recorder's 50 ms flushes make them
    w.close()


def _run(root: Path, name: str, *, n_steps: int = 200, summary: dict | None = None,
         meta: dict | None = None, last_k: int | None = None, lagging: int = 0,
         mode: str = "distributed") -> Path:
    folder = root / name
    folder.mkdir(parents=True)
    run_id = f"{name}-id"
    (folder / "scenario.json").write_text(json.dumps(
        {"run": {"id": run_id, "name": f"scen-{name}", "mode": mode, "n_steps": n_steps}}))
    if meta is not None:
        (folder / "run.json").write_text(json.dumps({"run_id": run_id, **meta}))
    if summary is not None:
        (folder / "summary.json").write_text(json.dumps(summary))
    if last_k is not None:
        _journal(folder, run_id, last_k, lagging)
    return folder


@pytest.fixture
def fabricated(tmp_path: Path) -> Path:
    dead = _dead_pid()
    me, me_start = os.getpid(), run_folder._proc_start(os.getpid())
    host = run_folder.socket.gethostname()
    _run(tmp_path, "a_ok", meta={"pid": dead, "host": host, "started": "2025-01-01T10:00:00"},
         summary={"status": "ok", "error": "", "rows": 201}, last_k=200)
    _run(tmp_path, "b_failed", meta={"pid": dead, "host": host, "started": "2025-01-01T10:01:00"},
         summary={"status": "failed", "error": "node 'controller' is gone", "rows": 38},
         last_k=40, lagging=3)
    _run(tmp_path, "c_interrupted", meta={"pid": dead, "host": host,
                                          "started": "2025-01-01T10:02:00"}, last_k=77)
    _run(tmp_path, "d_running", meta={"pid": me, "pid_start": me_start, "host": host,
                                      "started": "2025-01-01T10:03:00",
                                      "endpoints": {"listen": ["tcp/127.0.0.1:7447"]}},
         last_k=12)
    # Our pid, but a different process start time: the pid was reused, the run is gone.
    _run(tmp_path, "e_reused_pid", meta={"pid": me, "pid_start": (me_start or 0) + 12345,
                                         "host": host, "started": "2025-01-01T10:04:00"})
    _run(tmp_path, "f_old", last_k=5)  # no run.json, no summary: cannot tell
    _run(tmp_path, "g_other_host", meta={"pid": me, "host": host + "-elsewhere",
                                         "started": "2025-01-01T10:05:00"})
    (tmp_path / "not_a_run").mkdir()
    return tmp_path


def test_status_of_each_fabricated_run(fabricated: Path) -> None:
    listing = {r["id"]: r for r in runs.list_runs(fabricated)}
    assert set(listing) == {"a_ok-id", "b_failed-id", "c_interrupted-id", "d_running-id",
                            "e_reused_pid-id", "f_old-id", "g_other_host-id"}
    status = {k: v["status"] for k, v in listing.items()}
    assert status == {"a_ok-id": "ok", "b_failed-id": "failed",
                      "c_interrupted-id": "interrupted", "d_running-id": "running",
                      "e_reused_pid-id": "interrupted", "f_old-id": "unknown",
                      "g_other_host-id": "unknown"}
    assert listing["b_failed-id"]["error"] == "node 'controller' is gone"
    assert "gone" in listing["c_interrupted-id"]["error"]
    assert "elsewhere" in listing["g_other_host-id"]["error"]
    # Steps from the journal's tail: the last k every channel reached.
    assert listing["a_ok-id"]["steps"] == 200 and listing["a_ok-id"]["n_steps"] == 200
    assert listing["b_failed-id"]["steps"] == 37  # one channel lags 3 steps behind k = 40
    assert listing["c_interrupted-id"]["steps"] == 77
    assert listing["d_running-id"]["steps"] == 12
    assert listing["e_reused_pid-id"]["steps"] is None  # no journal
    assert listing["a_ok-id"]["name"] == "scen-a_ok"
    assert listing["a_ok-id"]["mode"] == "distributed"
    assert listing["d_running-id"]["endpoints"]["listen"] == ["tcp/127.0.0.1:7447"]
    # Oldest first (by the recorded start time).
    started = [r["started"] for r in runs.list_runs(fabricated) if r["id"] != "f_old-id"]
    assert started == sorted(started)


def test_steps_read_from_the_tail_of_a_big_journal(tmp_path: Path) -> None:
    folder = _run(tmp_path, "big", n_steps=5000, last_k=4321, lagging=1)
    assert (folder / "journal.msgpack").stat().st_size > 3 * TAIL_BYTES
    assert last_step(folder / "journal.msgpack") == 4320
    # A torn last record (the recorder was killed mid-write) is tolerated.
    with open(folder / "journal.msgpack", "ab") as f:
        f.write(b"\x93\xabplant/state\xc4\x40")
    assert last_step(folder / "journal.msgpack") == 4320


def test_sweep_folders_one_level_deeper(tmp_path: Path) -> None:
    sweep = tmp_path / "sweep"
    _run(sweep / "runs", "p1", summary={"status": "ok", "rows": 201}, last_k=200)
    _run(sweep / "runs", "p2", summary={"status": "ok", "rows": 201}, last_k=200)
    (sweep / "sweep.json").write_text("{}")
    assert sorted(r["id"] for r in runs.list_runs(sweep)) == ["p1-id", "p2-id"]
    assert [r["id"] for r in runs.list_runs(sweep / "runs" / "p1")] == ["p1-id"]


def test_write_run_json_marks_this_process_running(tmp_path: Path) -> None:
    folder = _run(tmp_path, "live", mode="distributed")
    info = run_folder.write_run_json(folder, "live-id", ["tcp/127.0.0.1:7447"], [], lowlatency=True)
    assert info["pid"] == os.getpid()
    on_disk = json.loads((folder / "run.json").read_text())
    assert on_disk["endpoints"] == {"listen": ["tcp/127.0.0.1:7447"], "connect": []}
    assert on_disk["mode"] == "distributed" and on_disk["lowlatency"] is True
    r = run_folder.run_info(folder)
    assert r["status"] == "running" and r["lowlatency"] is True


def test_cli_text_and_json(fabricated: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert runs.main([str(fabricated), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert {r["id"]: r["status"] for r in data}["c_interrupted-id"] == "interrupted"
    assert runs.main([str(fabricated)]) == 0
    text = capsys.readouterr().out
    lines = text.splitlines()
    assert lines[0].split()[:5] == ["ID", "NAME", "MODE", "STATUS", "STEPS"]
    row = next(line for line in lines if line.startswith("b_failed-id"))
    assert "failed" in row and "37/200" in row and "controller" in row
    row = next(line for line in lines if line.startswith("d_running-id"))
    assert "running" in row and f"suscosim tap {fabricated / 'd_running'}" in row


def test_cli_bad_or_empty_dir(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert runs.main([str(tmp_path / "missing")]) == 2
    assert "not a folder" in capsys.readouterr().err
    assert runs.main([str(tmp_path)]) == 0
    assert "no runs" in capsys.readouterr().out
