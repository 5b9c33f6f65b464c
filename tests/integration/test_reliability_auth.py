"""Issue #15 items 3, 4 and 9 on real processes over real Zenoh (loopback): forged control
and data messages from another process on the run's bus change nothing; a tap still reads
without the key; a run id live on the bus, or a folder in use, is refused with exit 2."""

from __future__ import annotations

import json
import os
import threading
import time

import numpy as np
import pytest

from cosim import keys
from cosim.bus import free_loopback_endpoint
from cosim.journal import read_journal
from cosim.step_message import expand, step_keyexprs
from cosim.table_writer import journal_table
from cosim.wire import decode, encode, encode_step
from tests.conftest import CH3_STEP, popen_suscosim, run_client, suscosim

pytestmark = pytest.mark.integration
SHORT = ("--set", "run.t_end=1.0", "--set", "run.stall_timeout_s=30.0")
N = 1000


def _table(folder) -> dict:
    table, bad = journal_table(read_journal(folder / "journal.msgpack").records)
    assert bad == 0
    return table


def test_forged_messages_on_the_bus_change_nothing_and_a_tap_still_reads(tmp_path) -> None:
    """#15 item 4: one forged ``start`` (n_steps 5) gave "ok" with 493 of 12001 rows;
    ``done`` on the nodes' ctl keys a fabricated summary; data for future steps wrong
    forces; an outside ``abort`` ended the run blaming the plant; a rogue scenario
    queryable was run. Here all of them at once, all through the run, from a peer on the
    run's own bus: the run ends ok with the table of an undisturbed run."""
    run_id = f"forge-{os.getpid()}"
    endpoint = free_loopback_endpoint()
    out, evil = tmp_path / "run", tmp_path / "evil"
    proc = popen_suscosim("run", str(CH3_STEP), "--out", str(out), "--quiet",
                          "--listen", endpoint, "--set", f'run.id="{run_id}"', *SHORT)
    bus = run_client(endpoint)
    k = lambda node, channel: keys.key(run_id, node, channel)  # noqa: E731
    rogue = encode("start", -1, 0.0, {"run": {"dir": str(evil), "n_steps": 5}})
    bus.serve(k(keys.ORCHESTRATOR, keys.SCENARIO), lambda: rogue)
    # A tap: no key, reads the signed messages all the same. The plant's state travels in
    # its step message (#28 item 2); the tap also hears this process's own forgeries, so it
    # keeps what it heard as (k, z_b) and the check below asks for the real run's values.
    heard: set[tuple[int, float]] = set()

    def tap(key: str, raw: bytes) -> None:
        for inner_key, msg in expand(key, decode(raw)):
            if inner_key == k("plant", "state"):
                heard.add((msg.k, float(msg.d["z_b"])))

    for keyexpr in step_keyexprs(k("plant", "state")):
        bus.subscribe(keyexpr, tap)
    stop = threading.Event()

    def inject() -> None:
        pubs = {name: bus.publisher(k(*name)) for name in [
            (keys.ORCHESTRATOR, keys.CLOCK), ("plant", keys.CTL), ("recorder", keys.CTL),
            ("tyre_road", keys.CTL), ("controller", keys.CTL), ("tyre_road", "force"),
            ("plant", "state"), ("plant", keys.RECORDS), ("tyre_road", keys.STEP),
            ("plant", keys.STEP)]}
        start = encode("start", -1, 0.0, {"n_steps": 5, "h": 0.001,
                                          "info": {"plant": {"n_corners": 1}}})
        done = encode("done", N, N * 1e-3, {"rejected": 0, "rows": 5, "stats": {}})
        abort = encode("abort", -1, 0.0, {"reason": "outside abort"})
        step = 0
        while not stop.is_set():
            pubs[keys.ORCHESTRATOR, keys.CLOCK](start)
            for node in ("plant", "recorder", "tyre_road", "controller"):
                pubs[node, keys.CTL](done)
            if step > 20:
                pubs[keys.ORCHESTRATOR, keys.CLOCK](abort)
            for j in range(step, step + 5):  # far and near future steps, plausible fields
                pubs["tyre_road", "force"](encode("data", j, j * 1e-3, {
                    "F_t": 1e5, "k_t": 1e9, "z_g": 0.5}))
                pubs["plant", "state"](encode("data", j, j * 1e-3, {
                    "z_b": 1.0, "v_b": 0.0, "z_w": 1.0, "v_w": 0.0}))
                # the same as the step messages the nodes read today (#28 item 2)
                pubs["tyre_road", keys.STEP](encode_step(j, j * 1e-3, [("force", encode(
                    "data", j, j * 1e-3, {"F_t": 1e5, "k_t": 1e9, "z_g": 0.5}))]))
                pubs["plant", keys.STEP](encode_step(j, j * 1e-3, [("state", encode(
                    "data", j, j * 1e-3, {"z_b": 1.0, "v_b": 0.0, "z_w": 1.0, "v_w": 0.0}))]))
            pubs["plant", keys.RECORDS](encode("records", step, 0.0, {"records": [
                ["state", encode("data", step, 0.0, {"z_b": [1.0, 2.0]})]]}))
            step += 5
            time.sleep(0.01)

    th = threading.Thread(target=inject, daemon=True)
    th.start()
    try:
        stdout, stderr = proc.communicate(timeout=150)
    finally:
        stop.set()
        th.join()
        bus.close()
    assert proc.returncode == 0, stdout + stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "ok" and summary["rows"] == N + 1
    rejected = summary["rejected_messages"]
    assert rejected["orchestrator"] > 0  # the forged done
    assert rejected["plant"] > 0 and rejected["tyre_road"] > 0  # forged data and clock
    assert rejected["recorder"] > 0  # the forged records batches
    assert not evil.exists()
    ref = suscosim("run", str(CH3_STEP), "--quiet", "--out", str(tmp_path / "ref"),
                   "--mode", "monolithic", *SHORT)
    assert ref.returncode == 0, ref.stdout + ref.stderr
    got, want = _table(out), _table(tmp_path / "ref")
    z_b = want["plant/state/z_b"]
    missed = [j for j in range(N + 1) if (j, float(z_b[j])) not in heard]
    assert not missed, f"the tap did not hear the plant's state of steps {missed[:20]}..."
    assert sorted(got) == sorted(want)
    for col in want:
        np.testing.assert_array_equal(got[col], want[col], err_msg=col)


def test_a_run_id_live_on_the_bus_and_a_folder_in_use_are_refused(tmp_path) -> None:
    """#15 item 3: a second run with the id of a live run (``--connect`` to it), or with the
    same ``--out``, ended "ok" with the other's data. Both are refused (exit 2) and the first
    run is untouched."""
    run_id = f"dup-{os.getpid()}"
    endpoint = free_loopback_endpoint()
    first = tmp_path / "first"
    a = popen_suscosim("run", str(CH3_STEP), "--out", str(first), "--quiet",
                       "--listen", endpoint, "--set", f'run.id="{run_id}"',
                       "--set", "run.t_end=3.0", "--set", "run.stall_timeout_s=30.0")
    try:
        deadline = time.monotonic() + 60
        while not (first / "journal.msgpack").exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert a.poll() is None, a.communicate()
        same_id = suscosim("run", str(CH3_STEP), "--quiet", "--out", str(tmp_path / "second"),
                           "--connect", endpoint, "--set", f'run.id="{run_id}"',
                           "--set", "run.t_end=3.0")
        same_out = suscosim("run", str(CH3_STEP), "--quiet", "--out", str(first),
                            "--mode", "monolithic", "--set", "run.t_end=0.1")
        stdout, stderr = a.communicate(timeout=150)
    finally:
        if a.poll() is None:
            a.kill()
    assert same_id.returncode == 2, same_id.stdout + same_id.stderr
    assert "already live on the bus" in same_id.stderr and "orchestrator" in same_id.stderr
    assert same_out.returncode == 2, same_out.stdout + same_out.stderr
    assert "in use by another run" in same_out.stderr
    assert a.returncode == 0, stdout + stderr
    summary = json.loads((first / "summary.json").read_text())
    assert summary["status"] == "ok" and summary["rows"] == 3001
    assert summary["channels"]["tyre_road/force/F_t"]["max"] == pytest.approx(
        (317.5 + 45.4) * 9.81 + 192000 * 0.02, rel=1e-9)


def test_a_node_started_elsewhere_takes_the_key_file_the_orchestrator_wrote(tmp_path) -> None:
    """#15 item 4: remote nodes get the run key by a key file (or the environment). With a
    node started by hand and no secret given, the orchestrator writes RUN/run.key (0600);
    the node started with --key-file takes part; without a key it exits 2 at once."""
    env_clean = {k: v for k, v in os.environ.items() if not k.startswith("SUSCOSIM_")}
    run_id = f"keyfile-{os.getpid()}"
    endpoint = free_loopback_endpoint()
    out = tmp_path / "run"
    import subprocess
    import sys

    from tests.conftest import ROOT

    def cli(*args: str) -> subprocess.Popen:
        return subprocess.Popen([sys.executable, "-m", "orchestrator", *args], cwd=ROOT,
                                env=dict(env_clean, PYTHONPATH=str(ROOT)), text=True,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE)

    main = cli("run", str(CH3_STEP), "--quiet", "--out", str(out), "--listen", endpoint,
               "--external", "plant", "--set", f'run.id="{run_id}"', *SHORT)
    try:
        key = out / "run.key"
        deadline = time.monotonic() + 60
        while not key.exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert key.stat().st_mode & 0o777 == 0o600
        keyless = cli("node", "plant", "--run", run_id, "--connect", endpoint)
        _, err = keyless.communicate(timeout=60)
        assert keyless.returncode == 2 and "--key-file" in err, err
        plant = cli("node", "plant", "--run", run_id, "--connect", endpoint,
                    "--key-file", str(key))
        stdout, stderr = main.communicate(timeout=150)
        p_out, p_err = plant.communicate(timeout=30)
    finally:
        for p in (main,):
            if p.poll() is None:
                p.kill()
    assert main.returncode == 0, stdout + stderr
    assert f"--key-file {key}" in stderr  # the orchestrator said where the key is
    assert plant.returncode == 0, p_out + p_err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "ok" and summary["rows"] == N + 1
