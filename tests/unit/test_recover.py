"""The orchestrator's table after a failed or interrupted run (``run_recovery.recover_table``): one
writer per table, and a stopped run that ends within seconds whatever its length."""

import time

import numpy as np

from cosim.journal import JournalWriter, read_journal
from cosim.table import export, read_table
from cosim.table_writer import journal_table
from cosim.wire import encode
from orchestrator import run_recovery, runner


def _journal(folder, n: int, pad: int = 0) -> None:
    import random

    rng = random.Random(1)  # values zstd cannot shrink (the journal's size is the point)
    w = JournalWriter(folder / "journal.msgpack", "r")
    for k in range(n):
        d = {"z": 1.0 * k} | ({"pad": [rng.random() for _ in range(pad)]} if pad else {})
        w.append("plant/state", encode("data", k, k * 1e-3, d))
        w.append("tyre_road/force", encode("data", k, k * 1e-3, {"F": -2.0 * k}))
    w.close()


def test_a_failed_run_rebuilds_its_table_from_the_journal(tmp_path):
    _journal(tmp_path, 50)
    rec = run_recovery.recover_table(tmp_path, since=time.time() - 60)
    assert rec["rows"] == 50 and rec["files"]["csv"].endswith("table.csv")
    assert read_table(tmp_path / "table.csv")["tyre_road/force/F"][49] == -98.0
    assert rec["stats"]["plant/state/z"]["max"] == 49.0


def test_the_recorders_fresh_table_is_taken_as_it_is(tmp_path):
    """A table the recorder exported after the run began that holds every journal step is
    not rebuilt (marked: its values here differ from the journal's, so a rebuild shows)."""
    _journal(tmp_path, 20)
    t0 = time.time() - 1.0
    table, _ = journal_table(read_journal(tmp_path / "journal.msgpack").records)
    table["plant/state/z"] = table["plant/state/z"] + 1000.0  # the recorder's (marked)
    export(table, tmp_path)
    rec = run_recovery.recover_table(tmp_path, since=t0)
    assert rec["note"] == "the table the recorder exported" and rec["rows"] == 20
    assert rec["stats"]["plant/state/z"]["min"] == 1000.0
    assert read_table(tmp_path / "table.csv")["plant/state/z"][0] == 1000.0


def test_a_table_older_than_the_run_or_short_of_the_journal_is_rebuilt(tmp_path):
    _journal(tmp_path, 20)
    table, _ = journal_table(read_journal(tmp_path / "journal.msgpack").records)
    stale = dict(table, **{"plant/state/z": table["plant/state/z"] + 1000.0})
    export(stale, tmp_path)
    rec = run_recovery.recover_table(tmp_path, since=time.time() + 5.0)  # before the run
    assert "note" not in rec and rec["stats"]["plant/state/z"]["min"] == 0.0
    short = {c: v[:10] for c, v in stale.items()}  # fresher, but 10 of the 20 steps
    export(short, tmp_path)
    rec = run_recovery.recover_table(tmp_path, since=time.time() - 60)
    assert rec["rows"] == 20 and rec["stats"]["plant/state/z"]["min"] == 0.0
    np.testing.assert_array_equal(read_table(tmp_path / "table.parquet")["plant/state/z"],
                                  np.arange(20.0))


def test_an_interrupted_long_run_leaves_its_table_to_suscosim_export(tmp_path, monkeypatch):
    monkeypatch.setattr(run_recovery, "INTERRUPT_REBUILD_BYTES", 20_000)
    _journal(tmp_path, 200, pad=20)
    assert (tmp_path / "journal.msgpack").stat().st_size > 20_000
    rec = run_recovery.recover_table(tmp_path, interrupted=True, since=time.time() - 60)
    assert rec["rows"] == 200 and rec["files"] == {}
    assert "suscosim export" in rec["note"] and str(tmp_path / "journal.msgpack") in rec["note"]
    assert not (tmp_path / "table.csv").exists()
    # the same journal, not interrupted (a node died): rebuilt whatever its size
    rec = run_recovery.recover_table(tmp_path, interrupted=False, since=time.time() - 60)
    assert rec["rows"] == 200 and (tmp_path / "table.csv").exists()


def test_an_interrupted_short_run_still_gets_its_table(tmp_path):
    _journal(tmp_path, 30)
    rec = run_recovery.recover_table(tmp_path, interrupted=True, since=time.time() - 60)
    assert rec["rows"] == 30 and len(read_table(tmp_path / "table.csv")["t"]) == 30


def test_the_summary_says_what_became_of_the_table():
    scenario = {"run": {"n_steps": 10, "id": "r", "mode": "distributed", "exchange": "x",
                        "coupling": "y", "h": 1e-3, "substeps": 1, "t_end": 0.01,
                        "nodes": ["plant"]}}
    note = "interrupted: the table was not rebuilt ...; run `suscosim export J`"
    summary = runner._summary(scenario, None, 1.0, {"rows": 7, "files": {}, "note": note},
                              "failed", "interrupted")
    assert summary["table_note"] == note and summary["rows"] == 7
    assert "table_note" not in runner._summary(scenario, None, 1.0, {"rows": 7}, "failed")


def test_a_recorder_elsewhere_is_waited_for_then_left_its_long_table(tmp_path, monkeypatch):
    """A recorder running elsewhere (compose, another machine), alive at the abort: its
    table is waited for; a long journal's is not rebuilt here when it does not come."""
    import threading

    monkeypatch.setattr(run_recovery, "INTERRUPT_REBUILD_BYTES", 20_000)
    _journal(tmp_path, 200, pad=20)
    rec = run_recovery.recover_table(tmp_path, since=time.time() - 60,
                                     recorder_elsewhere=True, wait_s=0.3)
    assert rec["files"] == {} and rec["rows"] == 200
    assert "running elsewhere" in rec["note"] and "suscosim export" in rec["note"]
    assert not (tmp_path / "table.csv").exists()
    # the recorder's table arrives while the orchestrator waits: taken as it is
    table, _ = journal_table(read_journal(tmp_path / "journal.msgpack").records)
    later = threading.Timer(0.3, export, (table, tmp_path))
    later.start()
    rec = run_recovery.recover_table(tmp_path, since=time.time() - 60,
                                     recorder_elsewhere=True, wait_s=5.0)
    later.join()
    assert rec["note"] == "the table the recorder exported" and rec["rows"] == 200


def test_the_tables_a_killed_recorder_was_writing_are_removed(tmp_path):
    """#32: the recorder writes table.csv/.parquet beside their place as the run goes; a
    killed one leaves them (hundreds of MB on a long run): recovery removes those whose
    writer is gone, not a live writer's."""
    import os
    import subprocess
    import sys

    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    dead = tmp_path / f".table.csv.{gone.pid}.7.tmp"
    live = tmp_path / f".table.parquet.{os.getpid()}.7.tmp"
    dead.write_text("half a table")
    live.write_text("being written")
    _journal(tmp_path, 5)
    rec = run_recovery.recover_table(tmp_path, since=time.time() - 60)
    assert rec["rows"] == 5 and not dead.exists() and live.exists()
