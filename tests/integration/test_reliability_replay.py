"""Issue #30 item 11 on real processes over real Zenoh: a keyless tap records run 1's signed
control messages (every node's ``ready``, ``progress``, ``done``, the recorder's statistics)
and replays them into run 2 of the same id under the same secret. Before each run instance
had its own nonce, run 2 ended "ok" at once with run 1's statistics; now every replayed
message is rejected and counted, and run 2 ends ok with its own numbers."""

from __future__ import annotations

import json
import os
import threading
import time

import pytest

from cosim import keys
from cosim.bus import free_loopback_endpoint
from tests.conftest import CH3_STEP, popen_suscosim, run_client

pytestmark = pytest.mark.integration
SHORT = ("--set", "run.t_end=0.5", "--set", "run.stall_timeout_s=30.0")


def test_control_messages_of_run_1_replayed_into_run_2_are_rejected(tmp_path,
                                                                    monkeypatch) -> None:
    monkeypatch.setenv("SUSCOSIM_KEY", "replay-test-shared-secret-0123456789")
    run_id = f"replay-{os.getpid()}"
    taped: list[tuple[str, bytes]] = []
    lock = threading.Lock()

    def tape(key: str, raw: bytes) -> None:
        with lock:
            taped.append((key, raw))

    ep1 = free_loopback_endpoint()
    out1 = tmp_path / "run1"
    p1 = popen_suscosim("run", str(CH3_STEP), "--out", str(out1), "--quiet", "--listen", ep1,
                        "--set", f'run.id="{run_id}"', *SHORT)
    tap = run_client(ep1)
    tap.subscribe(keys.key(run_id, "*", keys.CTL), tape)
    try:
        stdout, stderr = p1.communicate(timeout=150)
    finally:
        tap.close()
    assert p1.returncode == 0, stdout + stderr
    kinds = set()
    from cosim.wire import decode
    for _key, raw in taped:
        kinds.add(decode(raw).kind)
    assert {"ready", "done"} <= kinds, kinds  # the tap heard what the attack needs
    stats1 = json.loads((out1 / "summary.json").read_text())["channels"]

    ep2 = free_loopback_endpoint()
    out2 = tmp_path / "run2"
    p2 = popen_suscosim("run", str(CH3_STEP), "--out", str(out2), "--quiet", "--listen", ep2,
                        "--set", f'run.id="{run_id}"', "--set", "road.height=0.01", *SHORT)
    evil = run_client(ep2)
    stop = threading.Event()

    def replay() -> None:
        pubs = {key: evil.publisher(key) for key, _ in taped}
        while not stop.is_set():
            for key, raw in taped:
                pubs[key](raw)
            time.sleep(0.005)

    th = threading.Thread(target=replay, daemon=True)
    th.start()
    try:
        stdout, stderr = p2.communicate(timeout=150)
    finally:
        stop.set()
        th.join()
        evil.close()
    assert p2.returncode == 0, stdout + stderr
    summary = json.loads((out2 / "summary.json").read_text())
    assert summary["status"] == "ok"
    stats2 = summary["channels"]
    # its own numbers (the road of run 2 is half as high as run 1's), not run 1's
    assert stats1["tyre_road/force/z_g"]["peak"] == pytest.approx(0.02)
    assert stats2["tyre_road/force/z_g"]["peak"] == pytest.approx(0.01), \
        "run 2 ended with run 1's statistics"
    assert summary["rows"] == 501
    assert summary["rejected_messages"]["orchestrator"] > 0  # the replayed ones, counted
