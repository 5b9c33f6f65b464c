"""Issue #30 item 15 on real processes over real Zenoh: the error of a failed run names the
node that caused it. A producer paused 7 s was reported as "node 'recorder' made no
progress" (the one furthest behind); a signed abort sent by an insider as "node 'plant'
exited with code 1" (the node that obeyed it)."""

from __future__ import annotations

import json
import os
import signal
import time

import pytest

from cosim import auth as au
from cosim import keys
from cosim.bus import free_loopback_endpoint
from cosim.wire import decode, encode
from tests.conftest import CH3_STEP, node_pids, popen_suscosim, run_client

pytestmark = pytest.mark.integration


def _under_way(out, proc, size: int = 50_000) -> None:
    journal = out / "journal.msgpack"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and proc.poll() is None:
        if journal.exists() and journal.stat().st_size > size:
            return
        time.sleep(0.05)
    pytest.fail("run did not get under way")


def test_a_paused_producer_is_blamed_not_the_nodes_waiting_for_it(tmp_path) -> None:
    run_id = f"blame-pause-{os.getpid()}"
    out = tmp_path / "run"
    proc = popen_suscosim("run", str(CH3_STEP), "--out", str(out), "--quiet",
                          "--set", "run.t_end=30.0", "--set", f'run.id="{run_id}"',
                          "--set", "run.stall_timeout_s=3.0")  # lease = stall timeout
    pids: list[int] = []  # from 2 s (test_reliability_pause.py): 3 s is the 5 s case, sooner
    try:
        _under_way(out, proc)
        pids = node_pids(run_id, "plant")
        assert pids, "plant process not found"
        for pid in pids:
            os.kill(pid, signal.SIGSTOP)
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        for pid in pids:
            try:
                os.kill(pid, signal.SIGCONT)
            except ProcessLookupError:
                pass
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 1, stdout + stderr
    error = json.loads((out / "summary.json").read_text())["error"]
    assert "node 'plant'" in error, error
    assert "recorder" not in error.split(";")[0], error


def test_an_abort_an_insider_signs_is_said_to_be_foreign(tmp_path, monkeypatch) -> None:
    secret = "blame-test-shared-secret-0123456789"
    monkeypatch.setenv("SUSCOSIM_KEY", secret)
    run_id = f"blame-abort-{os.getpid()}"
    endpoint = free_loopback_endpoint()
    out = tmp_path / "run"
    proc = popen_suscosim("run", str(CH3_STEP), "--out", str(out), "--quiet",
                          "--listen", endpoint, "--set", "run.t_end=30.0",
                          "--set", f'run.id="{run_id}"', "--set", "run.stall_timeout_s=30.0")
    bus = run_client(endpoint)
    try:
        _under_way(out, proc)
        # the insider: the run's secret, the nonce read from the served scenario
        assert bus.wait_linked(), "the test's session never reached the run"
        reply, deadline = None, time.monotonic() + 20
        while reply is None and time.monotonic() < deadline:  # its queryable's declaration
            reply = bus.query(keys.key(run_id, keys.ORCHESTRATOR, keys.SCENARIO), timeout=2.0)
        assert reply is not None, "the run's scenario was never served"
        nonce = bytes.fromhex(decode(reply).d[au.SESSION_FIELD])
        key = au.RunKey(au.derive_run_key(secret.encode(), run_id), nonce)
        clock = keys.key(run_id, keys.ORCHESTRATOR, keys.CLOCK)
        pub = bus.publisher(clock)
        for _ in range(3):
            pub(key.sign(clock, encode("abort", -1, 0.0, {"reason": "insider says stop"})))
            time.sleep(0.05)
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        bus.close()
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 1, stdout + stderr
    error = json.loads((out / "summary.json").read_text())["error"]
    assert "did not send" in error and "insider says stop" in error, error
    assert "exited with code" not in error, error
