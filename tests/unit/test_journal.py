import os

from cosim.journal import JournalWriter, read_journal
from cosim.table import channel_stats
from cosim.table_writer import journal_table
from cosim.wire import encode


def _write(path, n, every=1):
    """``n`` steps of two channels, a segment every ``every`` steps."""
    w = JournalWriter(path, "run1")
    for k in range(n):
        w.append("plant/state", encode("data", k, k * 0.001, {"z_b": 0.001 * k}))
        w.append("tyre_road/force", encode("data", k, k * 0.001, {"F_t": [1.0 * k, 2.0 * k]}))
        if (k + 1) % every == 0:
            w.flush()
    w.close()


def test_journal_roundtrip_to_table(tmp_path):
    p = tmp_path / "j.msgpack"
    _write(p, 10, every=3)
    c = read_journal(p)
    assert c.run_id == "run1" and not c.torn and len(c.records) == 20
    table, bad = journal_table(c.records)
    assert bad == 0
    assert table["k"].tolist() == list(range(10))
    assert table["plant/state/z_b"][3] == 0.003
    assert table["tyre_road/force/F_t[1]"][4] == 8.0
    st = channel_stats(table)
    assert st["tyre_road/force/F_t[0]"]["max"] == 9.0


def test_a_torn_last_segment_loses_that_segment_and_says_how_many_records(tmp_path):
    p = tmp_path / "j.msgpack"
    _write(p, 10, every=2)  # 5 segments of 4 records
    with open(p, "r+b") as f:  # a crash in the middle of the last write
        f.truncate(os.path.getsize(p) - 7)
    c = read_journal(p)
    assert c.torn and "torn segment" in c.problem and "4 records" in c.problem
    assert len(c.records) == 16 and c.torn_records == 4 and not c.skipped
    table, _ = journal_table(c.records)
    assert len(table["t"]) == 8


def test_a_corrupted_last_segment_is_skipped_with_its_records_counted(tmp_path):
    p = tmp_path / "j.msgpack"
    _write(p, 6, every=2)
    data = bytearray(p.read_bytes())
    data[-6] ^= 0xFF  # inside the last segment's body: its CRC fails
    p.write_bytes(bytes(data))
    c = read_journal(p)
    assert len(c.records) == 8 and c.skipped_records == 4 and not c.torn
    assert c.problem.startswith("4 damaged record(s) skipped")


def test_a_stray_first_message_neither_crashes_nor_displaces_the_channel():
    """The first message of a channel lacks a field and has a list where the others have a
    scalar: it is left out (counted bad), the real messages make the table."""
    records = [("plant/state", encode("data", 0, 0.0, {"z_b": [9.0, 9.0]}))]
    records += [("plant/state", encode("data", k, k * 0.001, {"z_b": 0.1 * k, "v_b": -1.0 * k}))
                for k in range(5)]
    records += [("plant/state", encode("data", 5, 0.005, {"z_b": [1.0], "v_b": 0.0}))]
    table, bad = journal_table(records)
    assert bad == 2
    assert table["k"].tolist() == [0, 1, 2, 3, 4]
    assert table["plant/state/z_b"].tolist() == [0.1 * k for k in range(5)]
    assert table["plant/state/v_b"].tolist() == [-1.0 * k for k in range(5)]


def test_csv_is_what_the_csv_module_writes_and_reads_back_exactly(tmp_path):
    """Every float (subnormal, signed zero, inf, nan, 2**60) as ``csv.writer`` writes it,
    and read back to the same bits; a column name with a comma is quoted."""
    import csv
    import math

    import numpy as np

    from cosim.table import read_table, write_csv

    x = np.array([0.0, -0.0, 5e-324, 1 / 3, -np.inf, np.inf, np.nan, 2.0 ** 60, -1e300] * 1000)
    table = {"k": np.arange(x.size), "t": np.arange(x.size) * 1e-3, "a,b": x}
    write_csv(table, tmp_path / "fast.csv")
    with open(tmp_path / "ref.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(list(table))
        for row in zip(*(table[c].tolist() for c in table), strict=True):
            w.writerow(row)
    assert (tmp_path / "fast.csv").read_bytes() == (tmp_path / "ref.csv").read_bytes()
    back = read_table(tmp_path / "fast.csv")
    assert [math.copysign(1, v) for v in back["a,b"][:2]] == [1, -1]
    np.testing.assert_array_equal(back["a,b"], x)


def test_export_leaves_no_temporary_file_and_replaces_whole(tmp_path):
    import numpy as np

    from cosim.table import export, read_table

    (tmp_path / "table.csv").write_text("half a tab")  # e.g. left by a killed exporter
    table = {"k": np.arange(3), "t": np.arange(3) * 0.5, "x": np.ones(3)}
    paths = export(table, tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table.csv", "table.parquet"]
    for path in paths.values():
        np.testing.assert_array_equal(read_table(path)["x"], np.ones(3))


def test_read_table_keeps_the_columns_asked_for_and_names_a_bad_file(tmp_path):
    import numpy as np
    import pytest

    from cosim.errors import InputFileError
    from cosim.table import export, read_table

    table = {"k": np.arange(3), "t": np.arange(3) * 0.5, "plant/arm/ball_joint_z": np.ones(3),
             "plant/state/z_b": np.zeros(3)}
    paths = export(table, tmp_path)
    for path in paths.values():
        got = read_table(path, keep=lambda n: n.startswith("plant/arm/"))
        assert sorted(got) == ["k", "plant/arm/ball_joint_z", "t"]
        np.testing.assert_array_equal(got["plant/arm/ball_joint_z"], np.ones(3))
    bad = tmp_path / "bad.csv"
    bad.write_text("k,t,x\r\n0,0.0,1\r\n1,0.5\r\n")
    with pytest.raises(InputFileError, match=r"bad.csv:3: expected 3 fields, got 2"):
        read_table(bad)
    bad.write_text("k,t,x\r\n0,0.0,one\r\n")
    with pytest.raises(InputFileError, match=r"bad.csv:2: non-numeric value"):
        read_table(bad)
    bad.write_text("")
    with pytest.raises(InputFileError, match=r"bad.csv:1: no header row"):
        read_table(bad)
    torn = tmp_path / "torn.parquet"
    torn.write_bytes((tmp_path / "table.parquet").read_bytes()[:100])
    with pytest.raises(InputFileError, match=r"torn.parquet: not a readable Parquet file"):
        read_table(torn)
