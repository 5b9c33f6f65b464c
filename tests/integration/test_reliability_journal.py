"""#15 item 1, #32 on a real run's journal: one flipped byte in the middle costs the segment it
hits (the records of one ~50 ms flush), not the rest of the run, and the records lost are
counted exactly; ``suscosim export`` says so (exit 2, table written alongside) and ``suscosim
runs`` gives the same record count."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cosim.journal import read_journal, segment_index
from cosim.table import read_table

from ..conftest import CH3_STEP, suscosim

pytestmark = pytest.mark.integration


def test_flipped_byte_in_a_real_journal(tmp_path: Path) -> None:
    out = tmp_path / "run"
    res = suscosim("run", str(CH3_STEP), "--set", "run.t_end=2.0", "--out", str(out),
                   "--mode", "monolithic", "--quiet")
    assert res.returncode == 0, res.stdout + res.stderr
    journal = out / "journal.msgpack"
    intact = read_journal(journal)
    rows = len(read_table(out / "table.csv")["t"])
    table_csv = (out / "table.csv").read_bytes()
    data = bytearray(journal.read_bytes())
    segments = segment_index(journal)  # cut every ~50 ms of wall time: how many varies
    assert len(segments) >= 2, segments
    hit = len(data) // 2
    (segment,) = [s for s in segments if s[0] <= hit < s[0] + s[1]]
    data[hit] ^= 0x10
    journal.write_bytes(bytes(data))

    res = suscosim("export", str(journal))
    assert res.returncode == 2, res.stdout + res.stderr
    exported = json.loads(res.stdout)
    lost = exported["skipped_records"]
    assert str(journal) in res.stderr and f"{lost} damaged record(s) skipped" in res.stderr
    assert "Traceback" not in res.stderr
    assert exported["records"] == len(intact.records) - lost  # counted exactly
    assert lost == segment[2] < len(intact.records)  # the segment hit, not the rest
    assert (out / "table.csv").read_bytes() == table_csv  # never replaced by a smaller one
    recovered = read_table(out / "table.recovered.csv")
    assert rows - lost <= len(recovered["t"]) < rows  # at most the damaged segment's steps

    res = suscosim("runs", str(out), "--json")
    assert res.returncode == 0, res.stderr
    (info,) = json.loads(res.stdout)
    assert info["records"] == exported["records"] and info["skipped_records"] == lost
    assert f"{lost} damaged record(s) skipped" in info["error"]
