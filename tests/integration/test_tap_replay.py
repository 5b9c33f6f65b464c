"""Tap and replay over real Zenoh between real processes on loopback."""

from __future__ import annotations

import csv
import json
import re
import threading
import time
from pathlib import Path

import msgpack
import numpy as np
import pytest

from cosim.bus import ZenohBus, free_loopback_endpoint, zenoh_config
from cosim.journal import read_journal
from cosim.table import read_table
from orchestrator import runs

from ..conftest import CH3_STEP, popen_suscosim, suscosim

pytestmark = pytest.mark.integration

T_END = "3.0"  # s: long enough for a tap started after the run to see hundreds of steps
STATE = ("z_b", "v_b", "z_w", "v_w")


@pytest.fixture(scope="module")
def untapped(tmp_path_factory) -> Path:
    """The same run with nobody listening (the numbers a tap must not change)."""
    out = tmp_path_factory.mktemp("untapped") / "run"
    res = suscosim("run", str(CH3_STEP), "--out", str(out), "--quiet", "--set",
                   f"run.t_end={T_END}", "--set", 'run.id="tapbase"', timeout=180)
    assert res.returncode == 0, res.stdout + res.stderr
    return out


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _wait_for(path: Path, proc, timeout: float = 60.0) -> None:
    """Wait until ``path`` exists (a JSON file: until it parses; run.json is written in
    place, so it may be seen empty for a moment)."""
    deadline = time.monotonic() + timeout
    while True:
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, f"{path} not written"
        if path.exists():
            try:
                if path.suffix != ".json" or json.loads(path.read_text()) is not None:
                    return
            except ValueError:
                pass
        time.sleep(0.05)


def test_tap_sees_a_live_run_without_changing_it(tmp_path, untapped) -> None:
    out = tmp_path / "tapped"
    endpoint = free_loopback_endpoint()
    run = popen_suscosim("run", str(CH3_STEP), "--out", str(out), "--quiet", "--listen",
                         endpoint, "--set", f"run.t_end={T_END}", "--set", 'run.id="taptest"')
    try:
        _wait_for(out / "journal.msgpack", run)  # the nodes are up, the run is starting
        meta = json.loads((out / "run.json").read_text())
        assert meta["endpoints"]["listen"] == [endpoint] and meta["run_id"] == "taptest"
        # RUN is the run folder: the tap finds the run id and the endpoint in run.json.
        tap = suscosim("tap", str(out), "plant/state", "--count", "400", "--duration", "120",
                       "--csv", str(tmp_path / "tap.csv"), "--interval", "0.5", timeout=150)
        stdout, stderr = run.communicate(timeout=180)
    finally:
        if run.poll() is None:
            run.kill()
    assert tap.returncode == 0, tap.stdout + tap.stderr
    assert f"via {endpoint}" in tap.stderr
    assert "400 data" in tap.stdout and "0 undecodable" in tap.stdout
    assert run.returncode == 0, stdout + stderr
    rows = _rows(tmp_path / "tap.csv")
    assert len(rows) == 400
    assert {r["key"] for r in rows} == {"suscosim/taptest/plant/state"}
    ks = np.array([int(r["k"]) for r in rows])
    gaps = [(int(a), int(b)) for a, b in zip(ks[:-1], ks[1:], strict=True) if b != a + 1]
    # in order, none missed (once, in a full CI suite, step 15 was missing with the tap
    # joining at the run's start; not reproduced in 30 runs alone or under load: the gaps and
    # the tap's printout say more if it comes back)
    assert not gaps and len(ks) == 400, (gaps[:10], ks[:3].tolist(), tap.stderr[-2000:])
    # What the tap decoded is what the recorder recorded, to the last bit.
    table = read_table(out / "table.parquet")
    for name in STATE:
        tapped = np.array([float(r[name]) for r in rows])
        assert np.array_equal(tapped, table[f"plant/state/{name}"][ks]), name
    assert np.allclose([float(r["t"]) for r in rows], table["t"][ks], rtol=0, atol=1e-12)
    # The tapped run ends as the untapped one, with the same numbers.
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "ok" and summary["rejected_messages"]["plant"] == 0
    base = read_table(untapped / "table.csv")
    mine = read_table(out / "table.csv")
    assert set(base) == set(mine)
    for col in base:
        assert np.array_equal(base[col], mine[col]), col
    # And the folder lists as a finished run with every step.
    (info,) = runs.list_runs(out)
    assert (info["status"], info["steps"], info["n_steps"]) == ("ok", 3000, 3000)


def test_a_plain_zenoh_session_taps_a_default_run(tmp_path) -> None:
    """The README's "tap with plain Zenoh": a client session with Zenoh's own defaults
    otherwise (QoS lanes on, universal transport) gets a run's messages through its
    orchestrator, whose nodes' own links are low-latency without QoS (the default run)."""
    import zenoh

    out = tmp_path / "plain"
    endpoint = free_loopback_endpoint()
    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
    conf.insert_json5("connect/timeout_ms", "30000")  # run.json is written before it listens
    conf.insert_json5("scouting/multicast/enabled", "false")
    got: list[int] = []
    run = popen_suscosim("run", str(CH3_STEP), "--out", str(out), "--quiet", "--listen",
                         endpoint, "--set", f"run.t_end={T_END}",
                         "--set", 'run.id="plaintap"')
    try:
        _wait_for(out / "run.json", run)
        assert json.loads((out / "run.json").read_text())["lowlatency"] is True
        session = zenoh.open(conf)
        def state_k(sample) -> None:  # the README's example: plant/state from the step
            step = msgpack.unpackb(sample.payload.to_bytes())
            got.extend(msgpack.unpackb(raw)["k"] for channel, raw in
                       step["d"].get("msgs", []) if channel == "state")

        session.declare_subscriber("suscosim/plaintap/plant/step", state_k)
        stdout, stderr = run.communicate(timeout=180)
        session.close()
    finally:
        if run.poll() is None:
            run.kill()
    assert run.returncode == 0, stdout + stderr
    data = [k for k in got if k >= 0]
    assert len(data) > 500, len(got)
    assert data == list(range(data[0], data[0] + len(data)))  # in order, none missed


def test_replay_reaches_a_tap_step_by_step_despite_bad_messages(tmp_path, untapped) -> None:
    journal = untapped / "journal.msgpack"
    n_state = sum(1 for ch, _ in read_journal(journal).records if ch == "plant/state")
    endpoint = free_loopback_endpoint()
    csv_path = tmp_path / "replay.csv"
    # The default replay run id is '<original>-replay'.
    tap = popen_suscosim("tap", "tapbase-replay", "plant/state", "--listen", endpoint,
                         "--count", str(n_state), "--duration", "120", "--csv", str(csv_path))
    injector: ZenohBus | None = None
    stop = threading.Event()
    try:
        line = ""
        while "tapping" not in line:  # the tap has subscribed
            line = tap.stderr.readline()
            assert line, tap.communicate()
        assert "suscosim/tapbase-replay/plant/state" in line
        injector = ZenohBus(zenoh_config(connect=[endpoint]))
        put = injector.publisher("suscosim/tapbase-replay/plant/state")
        deadline = time.monotonic() + 30
        while not put.__self__.matching_status.matching:  # the tap's subscription arrived
            assert time.monotonic() < deadline, "the tap's subscriber never showed up"
            time.sleep(0.02)
        foreign = msgpack.packb({"v": 99, "kind": "data", "k": 5, "t": 0.005,
                                 "d": {"z_b": 1.0}})

        def inject() -> None:
            while not stop.is_set():
                put(b"\x93not a message")
                put(foreign)
                time.sleep(0.01)

        th = threading.Thread(target=inject, daemon=True)
        th.start()
        rep = suscosim("replay", str(untapped), "--fast", "--connect", endpoint, timeout=120)
        stdout, stderr = tap.communicate(timeout=120)
        stop.set()
        th.join()
    finally:
        stop.set()
        if injector is not None:
            injector.close()
        if tap.poll() is None:
            tap.kill()
    assert rep.returncode == 0, rep.stdout + rep.stderr
    assert f"replayed {len(read_journal(journal).records)} messages as run tapbase-replay" \
        in rep.stdout
    assert tap.returncode == 0, stdout + stderr
    assert "Traceback" not in stderr
    undecodable = int(re.search(r"(\d+) undecodable", stdout).group(1))
    assert undecodable > 0 and "unknown schema version 99" in stdout
    rows = _rows(csv_path)
    assert [int(r["k"]) for r in rows] == list(range(n_state))  # every step, in order
    table = read_table(untapped / "table.parquet")
    for name in STATE:
        assert np.array_equal([float(r[name]) for r in rows], table[f"plant/state/{name}"])


def test_tap_with_nobody_there_stops_after_duration(tmp_path) -> None:
    res = suscosim("tap", "nobody", "--connect", free_loopback_endpoint(), "--duration", "1",
                   timeout=60)
    assert res.returncode == 0, res.stderr
    assert "0 messages" in res.stdout and "Traceback" not in res.stderr


def test_client_tap_through_a_replay_started_first(tmp_path, untapped) -> None:
    """A client-mode tap (what a tap on another machine uses) gets everything through the
    one peer it connects to; the replay waits for it before publishing."""
    records = read_journal(untapped / "journal.msgpack").records
    n = {ch: sum(1 for c, _ in records if c == ch) for ch in ("tyre_road/force",
                                                           "controller/force")}
    endpoint = free_loopback_endpoint()
    rep = popen_suscosim("replay", str(untapped), "--fast", "--run", "clientrep", "--listen",
                         endpoint, "--wait", "60")
    try:
        tap = suscosim("tap", "clientrep", "*/force", "--connect", endpoint, "--mode",
                       "client", "--count", str(sum(n.values())), "--duration", "90", "--csv",
                       str(tmp_path / "f.csv"), timeout=120)
        rep_out, rep_err = rep.communicate(timeout=60)
    finally:
        if rep.poll() is None:
            rep.kill()
    assert tap.returncode == 0, tap.stdout + tap.stderr
    assert "(client session)" in tap.stderr
    assert rep.returncode == 0, rep_out + rep_err
    rows = _rows(tmp_path / "f.csv")
    by_key: dict[str, list[int]] = {}
    for r in rows:
        by_key.setdefault(r["key"], []).append(int(r["k"]))
    assert by_key == {f"suscosim/clientrep/{ch}": list(range(count))
                      for ch, count in n.items()}
