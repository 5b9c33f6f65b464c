"""A real run's local nodes are linked by the explicit mesh (orchestrator.local_mesh): each
node listens on its socket in the run's mesh folder and has no TCP socket at all (it reaches
the orchestrator and the other nodes over the folder's Unix sockets only); a tap still hears
the run through the orchestrator; the folder is gone when the run ends, also when it is
interrupted, and one left by an orchestrator killed outright is removed by the next run."""

from __future__ import annotations

import json
import signal
import tempfile
import time
from pathlib import Path

import pytest

from cosim.bus import free_loopback_endpoint
from orchestrator import local_mesh
from tests.conftest import CH3_STEP, node_pids, popen_suscosim, suscosim

pytestmark = pytest.mark.integration

NODES = ["plant", "tyre_road", "controller", "recorder"]


def _socket_inodes(pid: int) -> set[int]:
    inodes = set()
    for fd in Path(f"/proc/{pid}/fd").iterdir():
        try:
            target = fd.readlink().as_posix()
        except OSError:
            continue
        if target.startswith("socket:["):
            inodes.add(int(target[8:-1]))
    return inodes


def _table_inodes(path: str) -> dict[int, str]:
    """inode -> the line's address column (TCP: local address; Unix: the path, if any)."""
    out = {}
    lines = Path(path).read_text().splitlines()[1:]
    for line in lines:
        cols = line.split()
        if path.endswith("unix"):
            out[int(cols[6])] = cols[7] if len(cols) > 7 else ""
        else:
            out[int(cols[9])] = cols[1]
    return out


def _mesh_of(pid: int) -> Path | None:
    for folder in Path(tempfile.gettempdir()).glob(f"{local_mesh.PREFIX}*"):
        try:
            if int((folder / local_mesh.OWNER_FILE).read_text()) == pid:
                return folder
        except (OSError, ValueError):
            continue
    return None


def _under_way(proc, run_id: str, out: Path) -> Path:
    """The run's mesh folder, once every node is past its handshake and the run records."""
    deadline = time.monotonic() + 60
    while True:
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "the run never got under way"
        folder = _mesh_of(proc.pid)
        if folder and (out / "journal.msgpack").exists() and \
                all(len(node_pids(run_id, n)) == 1 for n in NODES):
            return folder
        time.sleep(0.2)


def test_the_nodes_talk_over_the_mesh_only(tmp_path) -> None:
    run_id = "meshrun"
    out = tmp_path / "run"
    endpoint = free_loopback_endpoint()
    # long enough to be checked while it runs on any machine; ended by SIGTERM (as Ctrl-C)
    proc = popen_suscosim("run", str(CH3_STEP), "--out", str(out), "--quiet", "--listen",
                          endpoint, "--set", "run.t_end=600", "--set", f'run.id="{run_id}"')
    try:
        folder = _under_way(proc, run_id, out)
        tap = suscosim("tap", run_id, "plant/state", "--connect", endpoint, "--count", "50",
                       "--duration", "30", timeout=60)
        assert tap.returncode == 0 and "50 data" in tap.stdout, tap.stdout + tap.stderr
        tcp = {**_table_inodes("/proc/net/tcp"), **_table_inodes("/proc/net/tcp6")}
        unix = _table_inodes("/proc/net/unix")
        for name in NODES:
            (pid,) = node_pids(run_id, name)
            mine = _socket_inodes(pid)
            assert not mine & set(tcp), f"{name} has a TCP socket"
            assert str(folder / f"{name}.sock") in {unix.get(i) for i in mine}, name
        assert (folder / "orchestrator.sock").exists()
        proc.send_signal(signal.SIGTERM)
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, stdout + stderr
    assert json.loads((out / "summary.json").read_text())["status"] == "failed"
    assert not folder.exists()  # removed at the end of the run, an interrupted one too


def test_a_killed_orchestrators_mesh_folder_goes_with_the_next_run(tmp_path) -> None:
    run_id = "meshkill"
    out = tmp_path / "killed"
    proc = popen_suscosim("run", str(CH3_STEP), "--out", str(out), "--quiet",
                          "--set", "run.t_end=600", "--set", f'run.id="{run_id}"',
                          "--set", "run.stall_timeout_s=2.0")
    try:
        folder = _under_way(proc, run_id, out)
        proc.kill()  # no chance to clean up
        proc.wait(timeout=30)
        assert folder.exists()
        deadline = time.monotonic() + 60  # its nodes see it gone and end
        while any(node_pids(run_id, n) for n in NODES):
            assert time.monotonic() < deadline, "the nodes outlived their orchestrator"
            time.sleep(0.2)
    finally:
        if proc.poll() is None:
            proc.kill()
    # Each node says why it ended: the process that started it is gone (cosim.orchestrator_presence;
    # it is checked before the liveliness token, whose drop takes 2 s to count).
    for name in NODES:
        log = (out / "logs" / f"{name}.log").read_text()
        assert f"its process {proc.pid}, which started this node, ended" in log, (name, log)
    res = suscosim("run", str(CH3_STEP), "--out", str(tmp_path / "next"), "--quiet",
                   "--set", "run.t_end=0.2", timeout=120)
    assert res.returncode == 0, res.stdout + res.stderr
    assert not folder.exists()
