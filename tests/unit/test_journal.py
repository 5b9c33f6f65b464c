import os

from cosim.journal import JournalWriter, read_journal
from cosim.table import build_table, channel_stats
from cosim.wire import encode


def _write(path, n):
    w = JournalWriter(path, "run1")
    for k in range(n):
        w.append("plant/state", encode("data", k, k * 0.001, {"z_b": 0.001 * k}))
        w.append("tyre_road/force", encode("data", k, k * 0.001, {"F_t": [1.0 * k, 2.0 * k]}))
    w.close()


def test_journal_roundtrip_to_table(tmp_path):
    p = tmp_path / "j.msgpack"
    _write(p, 10)
    c = read_journal(p)
    assert c.run_id == "run1" and not c.torn and len(c.records) == 20
    table, bad = build_table(c.records)
    assert bad == 0
    assert table["k"].tolist() == list(range(10))
    assert table["plant/state/z_b"][3] == 0.003
    assert table["tyre_road/force/F_t[1]"][4] == 8.0
    st = channel_stats(table)
    assert st["tyre_road/force/F_t[0]"]["max"] == 9.0


def test_torn_last_record_is_tolerated(tmp_path):
    p = tmp_path / "j.msgpack"
    _write(p, 10)
    size = os.path.getsize(p)
    with open(p, "r+b") as f:  # a crash in the middle of the last write
        f.truncate(size - 7)
    c = read_journal(p)
    assert c.torn and "torn" in c.problem
    assert len(c.records) == 19  # everything before the torn record
    table, _ = build_table(c.records)
    assert len(table["t"]) == 9  # only complete steps (step 9 lost its second channel)


def test_corrupted_last_record_is_skipped_and_reported(tmp_path):
    p = tmp_path / "j.msgpack"
    _write(p, 5)
    data = bytearray(p.read_bytes())
    data[-3] ^= 0xFF  # flip bits inside the last payload: crc mismatch
    p.write_bytes(bytes(data))
    c = read_journal(p)
    assert len(c.records) == 9 and c.skipped_records == 1 and "1 damaged record" in c.problem
