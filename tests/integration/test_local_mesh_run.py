"""A real run's local nodes are linked by the explicit mesh (orchestrator.local_mesh): each
node listens on its socket in the run's mesh folder and has no TCP socket at all (it reaches
the orchestrator and the other nodes over the folder's Unix sockets only); the folder is
gone when the run ends, and a tap still hears the run through the orchestrator."""

from __future__ import annotations

import json
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


def test_the_nodes_talk_over_the_mesh_only(tmp_path) -> None:
    run_id = "meshrun"
    out = tmp_path / "run"
    endpoint = free_loopback_endpoint()
    proc = popen_suscosim("run", str(CH3_STEP), "--out", str(out), "--quiet", "--listen",
                          endpoint, "--set", "run.t_end=20", "--set", f'run.id="{run_id}"')
    try:
        deadline = time.monotonic() + 60
        while True:  # under way: every node past its handshake, stepping
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "the run never got under way"
            folder = _mesh_of(proc.pid)
            if folder and (out / "journal.msgpack").exists() and \
                    all(len(node_pids(run_id, n)) == 1 for n in NODES):
                break
            time.sleep(0.2)
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
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, stdout + stderr
    assert json.loads((out / "summary.json").read_text())["status"] == "ok"
    assert not folder.exists()  # removed at the end of the run
