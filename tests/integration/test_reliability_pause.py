"""Issue #15 item 8: a node paused for a few seconds (SIGSTOP: a starved process) is judged by
the run's stall timeout, not by Zenoh's 2 s link lease. Before the fix a 4 s pause of the
recorder ended the run "node 'recorder' is gone" even with ``run.stall_timeout_s = 30``."""

from __future__ import annotations

import json
import os
import signal
import time

import pytest

from cosim.table import read_table
from orchestrator.local_nodes import local_lease_ms

from ..conftest import node_pids, popen_suscosim

pytestmark = pytest.mark.integration


def test_lease_follows_the_stall_timeout_within_bounds():
    assert local_lease_ms(5.0) == 5000
    assert local_lease_ms(30.0) == 30000
    assert local_lease_ms(0.5) == 2000
    assert local_lease_ms(600.0) == 30000


@pytest.mark.parametrize("node", ["recorder", "tyre_road"])
def test_a_paused_node_is_not_a_dead_node(tmp_path, ch3_step, node):
    run_id = f"pause-{node}-{os.getpid()}"
    out = tmp_path / node
    proc = popen_suscosim("run", str(ch3_step), "--out", str(out), "--quiet",
                          "--set", "run.t_end=6.0", "--set", f'run.id="{run_id}"',
                          "--set", "run.stall_timeout_s=30.0")
    try:
        journal = out / "journal.msgpack"
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            if journal.exists() and journal.stat().st_size > 100_000:
                break
            time.sleep(0.05)
        else:
            pytest.fail("run did not get under way")
        pids = node_pids(run_id, node)
        assert pids, f"{node} process not found"
        assert proc.poll() is None, "the run ended before its node was paused"
        for pid in pids:
            os.kill(pid, signal.SIGSTOP)
        time.sleep(4.0)  # twice the old 2 s lease + 1 s grace
        for pid in pids:
            os.kill(pid, signal.SIGCONT)
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, stdout + stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "ok"
    table = read_table(out / "table.csv")
    assert len(table["t"]) == 6001  # every step recorded: nothing lost while it was paused
