"""#15 item 5: a full disk or an unwritable folder ends the run promptly with a clear message,
the bus closed (no root needed: the writes are made to fail with ENOSPC)."""

from __future__ import annotations

import errno
import signal
from pathlib import Path

import pytest

from orchestrator import runner
from orchestrator.cli import main as cli_main

ROOT = Path(__file__).resolve().parents[2]
CH3 = ROOT / "scenarios" / "ch3_step_quarter_car.toml"
_write_text = Path.write_text


def _full_for(*names: str):
    """Path.write_text that fails like a full disk for files of these names."""
    def write_text(self: Path, *a, **kw):
        if self.name in names:
            raise OSError(errno.ENOSPC, "No space left on device", str(self))
        return _write_text(self, *a, **kw)
    return write_text


@pytest.fixture
def cli(capsys):
    def call(*args: str) -> tuple[int, str]:
        before = signal.getsignal(signal.SIGTERM)  # `run` installs its own handler
        try:
            code = cli_main(list(args))
        finally:
            signal.signal(signal.SIGTERM, before)
        return code, capsys.readouterr().err
    return call


def test_summary_writer_names_the_file_and_leaves_nothing_half_written(tmp_path, monkeypatch):
    monkeypatch.setattr(Path, "write_text", _full_for(".summary.json.tmp"))
    with pytest.raises(runner.SummaryWriteError) as exc:
        runner.write_summary(tmp_path, {"status": "ok"})
    assert str(tmp_path / "summary.json") in str(exc.value)
    assert "No space left on device (the disk is full)" in str(exc.value)
    assert list(tmp_path.iterdir()) == []


def test_full_disk_during_a_run_ends_it_with_both_errors(tmp_path, monkeypatch, cli):
    """The recorder's journal and then summary.json hit ENOSPC (the one-process engine's
    recorder): before, the summary write raised on the error path and the user got
    'internal error: OSError'."""

    def flush(self) -> None:
        if self._buf:
            raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr("cosim.journal.JournalWriter.flush", flush)
    monkeypatch.setattr(Path, "write_text", _full_for("summary.json", ".summary.json.tmp"))
    out = tmp_path / "run"
    code, err = cli("run", str(CH3), "--set", "run.t_end=0.05", "--out", str(out),
                    "--mode", "monolithic", "--quiet")
    assert code == 1, err
    assert "No space left on device" in err and f"cannot write {out / 'summary.json'}" in err
    assert "internal error: OSError" not in err.split("; and")[-1]
    assert not (out / "summary.json").exists() and not (out / "table.csv").exists()


def test_unwritable_run_folder_is_refused_before_anything_starts(tmp_path, cli):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    code, err = cli("run", str(CH3), "--out", str(blocker / "run"), "--mode", "monolithic",
                    "--quiet")
    assert code == 2, err
    assert "cannot write the run folder" in err and str(blocker) in err
    assert "internal error" not in err


def test_salvaged_table_is_removed_rather_than_left_truncated(tmp_path, monkeypatch):
    from cosim.journal import JournalWriter
    from cosim.wire import encode

    w = JournalWriter(tmp_path / "journal.msgpack", "r")
    for k in range(5):
        w.append("plant/state", encode("data", k, k * 1e-3, {"z": 1.0 * k}))
    w.close()

    def write_group(self):
        self._tmp["parquet"].write_bytes(b"PAR1")  # half a file, then the disk is full
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr("cosim.table_writer.TableWriter._write_group", write_group)
    from orchestrator.run_recovery import recover_table

    rec = recover_table(tmp_path)
    assert rec["rows"] == 5 and "No space left on device" in rec["error"]
    assert not (tmp_path / "table.csv").exists() and not (tmp_path / "table.parquet").exists()
