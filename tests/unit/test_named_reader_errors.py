"""#46 item 6: files that used to end in "internal error" (exit 1) are the file's named error
with exit 2: a Parquet load file whose time column is text or whose unit is not UTF-8, and a
duty folder whose duty.json holds text where numbers go."""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from tests.conftest import suscosim


def _exit_2_naming(res, name: str, words: str) -> None:
    assert res.returncode == 2, res.stdout + res.stderr
    assert name in res.stderr and words in res.stderr, res.stderr
    assert "internal error" not in res.stderr and "Traceback" not in res.stderr


def test_parquet_load_files_with_text_time_or_a_non_utf8_unit(tmp_path: Path) -> None:
    text = tmp_path / "text.parquet"
    pq.write_table(pa.table({"t": ["a", "b"], "x": ["c", "d"]}), text)
    _exit_2_naming(suscosim("fatigue", str(text), timeout=120), "text.parquet",
                   "time column 't' is not numeric")
    unit = tmp_path / "unit.parquet"
    schema = pa.schema([pa.field("t", pa.float64()),
                        pa.field("x", pa.float64(), metadata={b"unit": b"\xff\xfe"})])
    pq.write_table(pa.table({"t": [0.0, 0.1], "x": [1.0, 2.0]}, schema=schema), unit)
    _exit_2_naming(suscosim("fatigue", str(unit), timeout=120), "unit.parquet",
                   "unit is not UTF-8")


def test_a_duty_json_with_text_where_numbers_go(tmp_path: Path) -> None:
    duty = tmp_path / "duty"
    duty.mkdir()
    (duty / "duty.json").write_text(json.dumps(
        {"name": "d", "critical_node_id": 1,
         "events": [{"name": "e", "repeats": "many", "share_at_critical": "abc"}]}))
    _exit_2_naming(suscosim("report", str(duty), timeout=120), "duty.json",
                   "a value of the wrong type")
    assert not (duty / "report.html").exists()


def test_random_bytes_as_a_runs_scenario_json_for_batch_fatigue(tmp_path: Path) -> None:
    run = tmp_path / "run"
    run.mkdir()
    (run / "summary.json").write_text(json.dumps({"status": "ok"}))
    (run / "scenario.json").write_bytes(bytes(range(256)) * 2)
    _exit_2_naming(suscosim("fatigue", str(run), timeout=120), "scenario.json",
                   "not a text (utf-8) file")
