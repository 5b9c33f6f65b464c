"""#15 item 1 on a real run's journal: one flipped byte in the middle costs one record, not the
rest of the run; ``suscosim export`` says so (exit 2, table written alongside) and ``suscosim
runs`` gives the same record count."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cosim.journal import read_journal
from cosim.table import read_table

from ..conftest import CH3_STEP, suscosim

pytestmark = pytest.mark.integration


def test_flipped_byte_in_a_real_journal(tmp_path: Path) -> None:
    out = tmp_path / "run"
    res = suscosim("run", str(CH3_STEP), "--set", "run.t_end=0.3", "--out", str(out),
                   "--mode", "monolithic", "--quiet")
    assert res.returncode == 0, res.stdout + res.stderr
    journal = out / "journal.msgpack"
    intact = read_journal(journal)
    rows = len(read_table(out / "table.csv")["t"])
    table_csv = (out / "table.csv").read_bytes()
    data = bytearray(journal.read_bytes())
    data[len(data) // 2] ^= 0x10
    journal.write_bytes(bytes(data))

    res = suscosim("export", str(journal))
    assert res.returncode == 2, res.stdout + res.stderr
    assert str(journal) in res.stderr and "1 damaged record(s) skipped" in res.stderr
    assert "Traceback" not in res.stderr
    exported = json.loads(res.stdout)
    assert exported["records"] == len(intact.records) - 1 and exported["skipped_records"] == 1
    assert (out / "table.csv").read_bytes() == table_csv  # never replaced by a smaller one
    recovered = read_table(out / "table.recovered.csv")
    assert rows - 1 <= len(recovered["t"]) <= rows  # at most the damaged record's step lost

    res = suscosim("runs", str(out), "--json")
    assert res.returncode == 0, res.stderr
    (info,) = json.loads(res.stdout)
    assert info["records"] == exported["records"] and info["skipped_records"] == 1
    assert "1 damaged record(s) skipped" in info["error"]
