"""#15 item 5 for real: a distributed run on a 200 KiB tmpfs (needs root to mount it; skipped
otherwise; tests/unit/test_reliability_disk.py covers the same without root). Before, the
orchestrator printed 'internal error: OSError: [Errno 28]' and never exited."""

from __future__ import annotations

import json
import os
import re
import subprocess
from pathlib import Path

import pytest

from ..conftest import CH3_STEP, suscosim

pytestmark = pytest.mark.integration


@pytest.fixture
def full_disk(tmp_path: Path):
    if os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root")
    mnt = tmp_path / "full"
    mnt.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=200k", "tmpfs", str(mnt)],
                      capture_output=True).returncode != 0:
        pytest.skip("cannot mount a tmpfs here")
    try:
        yield mnt
    finally:
        subprocess.run(["umount", "-l", str(mnt)], capture_output=True)


def _processes_of(run_id: str) -> list[int]:
    pids = []
    for d in Path("/proc").iterdir():
        try:
            if d.name.isdigit() and run_id.encode() in (d / "cmdline").read_bytes():
                pids.append(int(d.name))
        except OSError:
            continue
    return pids


def test_a_full_disk_ends_a_distributed_run_with_a_clear_message(full_disk: Path) -> None:
    out = full_disk / "run"
    # the timeout only guards the suite against the old hang; nothing is asserted on time
    res = suscosim("run", str(CH3_STEP), "--set", "run.t_end=2", "--out", str(out),
                   "--quiet", timeout=120)
    assert res.returncode == 1, res.stdout + res.stderr
    assert "No space left on device" in res.stderr and "(the disk is full)" in res.stderr
    assert "internal error" not in res.stderr, res.stderr
    # the recorder says it (its table files aside are removed, which may leave room for the
    # summary) or the summary could not be written; either way nothing is half written
    assert "node 'recorder'" in res.stderr or f"cannot write {out / 'summary.json'}" in \
        res.stderr, res.stderr
    if (out / "summary.json").exists():
        assert json.loads((out / "summary.json").read_text())["status"] == "failed"
    run_id = re.search(r"run (\S+) ->", res.stdout).group(1)
    assert _processes_of(run_id) == []  # every node ended with its run
