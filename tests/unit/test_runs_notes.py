"""#30 items 8 and 15 in ``runs``, ``run.json`` and ``export``: a truncated journal of an ok
run is noted, each run's folder is shown, run.json says the run ended, and an export of a
folder with no run is a sentence."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from cosim import run_folder
from cosim.journal import JournalWriter
from cosim.wire import encode
from orchestrator import runs
from orchestrator.export import main as export_main


def _ok_run(folder: Path, steps: int, n_steps: int) -> Path:
    folder.mkdir(parents=True)
    (folder / "scenario.json").write_text(json.dumps({"run": {"id": "t", "n_steps": n_steps}}))
    (folder / "summary.json").write_text(json.dumps({"status": "ok", "rows": n_steps + 1}))
    w = JournalWriter(folder / "journal.msgpack", "t")
    for k in range(steps + 1):
        w.append("plant/state", encode("data", k, k * 1e-3, {"z": float(k)}))
        if k % 100 == 99:
            w.flush()
    w.close()
    return folder


def test_a_truncated_journal_of_an_ok_run_is_said(tmp_path: Path) -> None:
    folder = _ok_run(tmp_path / "a", 3000, 6000)
    size = os.path.getsize(folder / "journal.msgpack")
    with open(folder / "journal.msgpack", "r+b") as f:
        f.truncate(size // 2)  # cut mid-segment
    info = run_folder.run_info(folder)
    assert info["status"] == "ok" and info["steps"] < 1600
    assert "torn segment" in info["error"]
    assert f"ends at step {info['steps']} of 6000" in info["error"]
    text = runs.format_table(runs.list_runs(tmp_path))
    assert str(folder) in text and "ends at step" in text  # the DIR and NOTE columns
    whole = run_folder.run_info(_ok_run(tmp_path / "b", 6000, 6000))
    assert whole["error"] == "" and whole["steps"] == 6000


def test_run_json_says_the_run_ended(tmp_path: Path) -> None:
    (tmp_path / "scenario.json").write_text(json.dumps({"run": {"id": "x", "mode": "m"}}))
    run_folder.write_run_json(tmp_path, "x", [], [])
    assert json.loads((tmp_path / "run.json").read_text())["state"] == "started"
    run_folder.mark_run_ended(tmp_path, "ok")
    meta = json.loads((tmp_path / "run.json").read_text())
    assert meta["state"] == "ok" and meta["ended"] and meta["run_id"] == "x"


def test_export_of_a_folder_with_no_run_is_a_sentence(tmp_path: Path, capsys) -> None:
    assert export_main([str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "not a run folder" in err and "Errno" not in err
    assert export_main([str(tmp_path / "nothing")]) == 2
    assert "no such journal or run folder" in capsys.readouterr().err
    assert export_main([str(tmp_path), "--format", "csv"]) == 2
    assert "not a run folder" in capsys.readouterr().err


def test_an_export_of_some_channels_does_not_replace_another(tmp_path: Path, capsys) -> None:
    folder = tmp_path / "run"
    folder.mkdir()
    w = JournalWriter(folder / "journal.msgpack", "t")
    for k in range(50):
        w.append("plant/arm", encode("data", k, k * 1e-3, {"a": float(k), "b": -1.0 * k}))
    w.close()
    assert export_main([str(folder)]) == 0
    capsys.readouterr()
    assert export_main([str(folder), "--format", "csv", "--channels", "plant/arm/a"]) == 0
    first = json.loads(capsys.readouterr().out)["files"]["csv"]
    assert export_main([str(folder), "--format", "csv", "--channels", "plant/arm/b"]) == 0
    second = json.loads(capsys.readouterr().out)["files"]["csv"]
    assert first != second and Path(first).is_file() and Path(second).is_file()
    assert Path(first).read_text().splitlines()[0] == "t,plant/arm/a [N]"
    assert export_main([str(folder), "--format", "csv"]) == 0  # all: table.csv
    assert json.loads(capsys.readouterr().out)["files"]["csv"].endswith("export/table.csv")


def test_a_result_file_is_replaced_whole_or_not_at_all(tmp_path) -> None:
    """cosim.run_folder.replaced: the new file appears only when its block ends; an error in
    the block leaves the old file as it was and no temporary file beside it."""
    path = tmp_path / "results.csv"
    path.write_text("old\n")
    with run_folder.replaced(path, newline="") as fh:
        fh.write("new,1\r\n")
        assert path.read_text() == "old\n"  # not yet
    assert path.read_bytes() == b"new,1\r\n"
    with pytest.raises(RuntimeError), run_folder.replaced(path) as fh:
        fh.write("half")
        raise RuntimeError("a writer failed")
    assert path.read_bytes() == b"new,1\r\n" and sorted(p.name for p in tmp_path.iterdir()) == [
        "results.csv"]
