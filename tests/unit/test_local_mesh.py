"""The explicit mesh of a run's local nodes (orchestrator.local_mesh): every pair of members
linked by exactly one side, the sockets in a private folder, removed afterwards."""

from __future__ import annotations

import itertools
import os
import stat
from pathlib import Path

import pytest

from orchestrator.local_mesh import ORCHESTRATOR, SOCKET_PATH_MAX, LocalMesh

NAMES = ["plant", "tyre_road", "controller", "recorder", "fatigue"]


def _path(ep: str) -> str:
    assert ep.startswith("unixsock-stream/"), ep
    return ep.removeprefix("unixsock-stream/")


def test_every_pair_is_linked_once_by_one_side() -> None:
    mesh = LocalMesh.create(NAMES)
    try:
        owner = {_path(mesh.listen(n)): n for n in [ORCHESTRATOR, *NAMES]}
        assert len(owner) == len(NAMES) + 1  # one socket each
        links = [frozenset((n, owner[_path(ep)])) for n in NAMES for ep in mesh.connect(n)]
        pairs = {frozenset(p) for p in itertools.combinations([ORCHESTRATOR, *NAMES], 2)}
        assert sorted(map(sorted, links)) == sorted(map(sorted, pairs))  # each pair, once
        assert mesh.connect("plant") == [mesh.listen(ORCHESTRATOR)]
    finally:
        mesh.remove()


def test_the_folder_is_private_and_removed() -> None:
    mesh = LocalMesh.create(NAMES)
    folder = mesh.folder
    assert stat.S_IMODE(folder.stat().st_mode) == 0o700
    assert all(Path(_path(mesh.listen(n))).parent == folder for n in NAMES)
    mesh.remove()
    assert not folder.exists()
    mesh.remove()  # idempotent


def test_a_deep_tmpdir_falls_back_to_tmp_and_leaves_nothing_there(monkeypatch,
                                                                    tmp_path) -> None:
    deep = tmp_path / ("d" * 90)
    deep.mkdir()
    monkeypatch.setenv("TMPDIR", str(deep))
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", None)  # read TMPDIR again
    mesh = LocalMesh.create(NAMES)
    try:
        assert mesh.folder.parent == Path("/tmp")
        assert all(len(str(mesh.socket(n)).encode()) <= SOCKET_PATH_MAX for n in NAMES)
        assert os.listdir(deep) == []
    finally:
        mesh.remove()


def test_a_socket_path_too_long_everywhere_is_refused(monkeypatch) -> None:
    with pytest.raises(ValueError, match=f"longer than {SOCKET_PATH_MAX} bytes"):
        LocalMesh.create(["x" * 120])


def test_a_member_name_must_be_a_plain_file_name() -> None:
    mesh = LocalMesh.create(["plant"])
    try:
        with pytest.raises(ValueError, match="plain file name"):
            mesh.socket("../x")
    finally:
        mesh.remove()


def test_a_killed_orchestrators_folder_is_removed_by_the_next_run() -> None:
    import subprocess
    import sys

    from orchestrator import local_mesh

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    stale = LocalMesh.create(["plant"])
    (stale.folder / local_mesh.OWNER_FILE).write_text(dead.stdout.strip())  # gone now
    (stale.folder / "plant.sock").write_text("")
    live = LocalMesh.create(["plant"])  # this process: alive
    try:
        assert not stale.folder.exists()
        assert live.folder.is_dir()
        assert local_mesh.remove_stale() == []
        assert live.folder.is_dir()
    finally:
        live.remove()
        stale.remove()
