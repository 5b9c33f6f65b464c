"""A run across three "machines" (Linux network namespaces), and a network partition.

Namespace A runs ``suscosim router``, B the plant node (``suscosim node plant``, a Zenoh
client of the router), C the orchestrator with the other nodes (``suscosim run --external
plant``). B and C reach each other only through the router (see ``netns.py``). Root only:
skipped with the reason otherwise.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from cosim.journal import read_journal
from cosim.table import read_table
from cosim.table_writer import journal_table

from ..conftest import CH3_STEP, ROOT, suscosim
from .netns import ADDR, MAIN, PLANT, ROUTER, ROUTER_ADDR, Topology, unavailable

pytestmark = [pytest.mark.netns, pytest.mark.long, pytest.mark.integration,
              pytest.mark.usefixtures("shared_run_secret")]

PORT = 7447
SHORT = ["--set", "run.t_end=0.5", "--set", "road.t_start=0.1"]  # the step inside the run


@pytest.fixture
def topo():
    reason = unavailable()
    if reason:
        pytest.skip(reason)
    t = Topology()
    try:
        yield t
    finally:
        t.close()  # always: kills what runs inside, deletes namespaces and links


def _cli(t: Topology, where: str, *args: str, **kw) -> subprocess.Popen:
    env = dict(os.environ, PYTHONPATH=str(ROOT), PYTHONUNBUFFERED="1")
    argv = t.cmd(where, [sys.executable, "-m", "orchestrator", *args])
    return subprocess.Popen(argv, cwd=ROOT, env=env, text=True, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, **kw)


def _start_router(t: Topology) -> subprocess.Popen:
    router = _cli(t, ROUTER, "router", "--listen", f"tcp/0.0.0.0:{PORT}")
    line = router.stdout.readline()  # printed once the listener is bound ("" if it died)
    assert "listening on" in line, line + router.stderr.read()
    return router


def _start_plant(t: Topology, run_id: str) -> subprocess.Popen:
    return _cli(t, PLANT, "node", "plant", "--run", run_id,
                "--connect", f"tcp/{ROUTER_ADDR[PLANT]}:{PORT}")


def _run_main(t: Topology, run_id: str, out: Path, *extra: str) -> subprocess.Popen:
    return _cli(t, MAIN, "run", str(CH3_STEP), "--quiet", "--out", str(out),
                "--connect", f"tcp/{ROUTER_ADDR[MAIN]}:{PORT}", "--external", "plant",
                "--set", f'run.id="{run_id}"', *extra)


def test_run_across_namespaces_equals_single_host_run(topo, tmp_path):
    # The plant's namespace has no route to the orchestrator's: only the router joins them.
    route = subprocess.run(topo.cmd(PLANT, ["ip", "route", "get", ADDR[MAIN]]),
                           capture_output=True, text=True)
    assert route.returncode != 0 and "unreachable" in route.stderr.lower(), route
    router = _start_router(topo)
    run_id = f"netns-{os.getpid()}"
    plant = _start_plant(topo, run_id)
    main = _run_main(topo, run_id, tmp_path / "ns", *SHORT)
    out, err = main.communicate(timeout=180)
    assert main.returncode == 0, out + err
    p_out, p_err = plant.communicate(timeout=30)
    assert plant.returncode == 0, p_out + p_err
    assert router.poll() is None  # still serving
    summary = json.loads((tmp_path / "ns" / "summary.json").read_text())
    assert summary["status"] == "ok" and summary["n_steps"] == 500
    assert not (tmp_path / "ns" / "logs" / "plant.log").exists()  # not started in C

    single = suscosim("run", str(CH3_STEP), "--quiet", "--out", str(tmp_path / "one"),
                      "--mode", "monolithic", *SHORT)
    assert single.returncode == 0, single.stdout + single.stderr
    across = read_table(tmp_path / "ns" / "table.parquet")
    here = read_table(tmp_path / "one" / "table.parquet")
    assert sorted(across) == sorted(here) and len(here["t"]) == 501
    assert np.ptp(here["plant/state/z_b"]) > 1e-3  # the step happened inside the run
    for col in here:
        np.testing.assert_allclose(across[col], here[col], rtol=1e-12, atol=1e-12,
                                   err_msg=col)


def test_partitioned_plant_ends_the_run_naming_it_and_keeps_the_record(topo, tmp_path):
    _start_router(topo)
    run_id = f"netcut-{os.getpid()}"
    out_dir = tmp_path / "cut"
    _start_plant(topo, run_id)
    # Long enough to be cut mid-run; a stall timeout far above the liveliness lease, so the
    # run must end because the plant is seen gone, not because nothing progresses.
    main = _run_main(topo, run_id, out_dir, "--set", "run.t_end=120.0",
                     "--set", "run.stall_timeout_s=60.0")
    journal = out_dir / "journal.msgpack"
    deadline = time.monotonic() + 90
    while time.monotonic() < deadline and main.poll() is None:
        if journal.exists() and journal.stat().st_size > 200_000:
            break
        time.sleep(0.1)
    else:
        pytest.fail("run did not get under way: " + "".join(main.communicate(timeout=10)))
    topo.cut(PLANT)
    out, err = main.communicate(timeout=90)  # bounded: a hang fails here
    assert main.returncode == 1, out + err
    assert "plant" in err and "Traceback" not in err, err
    assert "no progress" not in err, err  # seen gone (liveliness), not by the stall timeout
    summary = json.loads((out_dir / "summary.json").read_text())
    assert summary["status"] == "failed" and "plant" in summary["error"]
    contents = read_journal(journal)
    table, _ = journal_table(contents.records)
    assert 0 < len(table["t"]) < 120_001
    assert summary["rows"] == len(table["t"])
    csv = read_table(out_dir / "table.csv")
    assert len(csv["t"]) == len(table["t"])
    np.testing.assert_array_equal(csv["plant/state/z_w"], table["plant/state/z_w"])
