"""A node killed at start-up, before the others have joined the run's mesh: the orchestrator's
abort must still reach every node (it says it again while it waits for them to end). Before,
the others had subscribed after the abort was said and sat in their handshake until the
orchestrator's grace period ran out and it terminated them."""

from __future__ import annotations

import json
import os
import signal
import time

import pytest

from ..conftest import node_pids, popen_suscosim

pytestmark = pytest.mark.integration


def test_a_plant_killed_at_start_up_ends_every_other_node_by_the_abort(tmp_path, ch3_step):
    run_id = f"startkill-{os.getpid()}"
    out = tmp_path / "run"
    proc = popen_suscosim("run", str(ch3_step), "--out", str(out), "--quiet",
                          "--set", "run.t_end=60.0", "--set", f'run.id="{run_id}"')
    try:
        deadline = time.monotonic() + 60
        while not (pids := node_pids(run_id, "plant")) and time.monotonic() < deadline:
            time.sleep(0.01)
        assert pids, "the plant process never started"
        time.sleep(0.2)  # the others are starting: importing, opening their sessions
        os.kill(pids[0], signal.SIGKILL)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 1, err
    assert "node 'plant' exited with code -9" in err, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and "plant" in summary["error"]
    for node in ("controller", "tyre_road", "recorder"):
        log = (out / "logs" / f"{node}.log").read_text()
        # each ended on the abort, none was terminated (a terminated node dumps its stacks)
        assert "run aborted by the orchestrator: node 'plant'" in log, (node, log[-2000:])
        assert "Current thread" not in log, (node, log[-2000:])
