"""#15 item 1: a damaged record costs that record only, and every reader agrees (synthetic
journals; the real-run version is tests/integration/test_reliability_journal.py)."""

from __future__ import annotations

import zlib
from pathlib import Path

import msgpack

from cosim import run_folder
from cosim.journal import JournalWriter, last_step, read_journal
from cosim.wire import encode
from orchestrator.cli import main as cli_main

CHANNELS = ("plant/state", "tyre_road/force")


def _write(path: Path, n: int) -> list[tuple[str, bytes]]:
    w = JournalWriter(path, "rel")
    records = []
    for k in range(n):
        for ch in CHANNELS:
            raw = encode("data", k, k * 1e-3, {"z": 0.001 * k, "F": [1.0 * k, -2.0 * k]})
            w.append(ch, raw)
            records.append((ch, raw))
    w.close()
    return records


def _header_len(path: Path) -> int:
    u = msgpack.Unpacker()
    u.feed(path.read_bytes())
    next(u)
    return u.tell()


def test_every_single_byte_flip_costs_one_record_at_most(tmp_path: Path) -> None:
    """Flip each byte after the header in turn: the reader never raises and keeps every
    record but the one hit, in order (today's reader stopped at the first bad record)."""
    p = tmp_path / "j.msgpack"
    original = _write(p, 6)
    clean = p.read_bytes()
    for i in range(_header_len(p), len(clean)):
        data = bytearray(clean)
        data[i] ^= 0x5A
        p.write_bytes(bytes(data))
        c = read_journal(p)
        kept = c.records
        assert len(kept) == len(original) - 1, (i, c.problem)
        assert all(r in original for r in kept), i  # nothing forged by the damage
        assert [original.index(r) for r in kept] == sorted(original.index(r) for r in kept)
        assert c.skipped_records == 1 or (c.torn and kept == original[:-1]), (i, c.problem)


def test_a_flipped_length_byte_mid_journal_is_not_taken_for_a_torn_tail(tmp_path: Path) -> None:
    p = tmp_path / "j.msgpack"
    original = _write(p, 200)
    data = bytearray(p.read_bytes())
    mid = data.find(b"\xc4", len(data) // 2)  # the bin length marker of a payload
    data[mid + 1] = 0xFF  # the payload now claims 255 bytes: the frame swallows its successors
    p.write_bytes(bytes(data))
    c = read_journal(p)
    assert not c.torn and c.skipped_records == 1 and len(c.records) == len(original) - 1
    assert "1 damaged record(s) skipped at byte" in c.problem


def test_a_flipped_channel_name_is_caught_by_the_crc(tmp_path: Path) -> None:
    """Version 2 journals cover the channel name too (version 1 covered the payload only: a
    record of channel 'plant/stbte' would have made a channel of one step, and a table of one
    row)."""
    p = tmp_path / "j.msgpack"
    original = _write(p, 50)
    data = bytearray(p.read_bytes())
    i = data.find(b"plant/state", len(data) // 2)
    data[i + 8] ^= 0x03  # 'a' -> 'b'
    p.write_bytes(bytes(data))
    c = read_journal(p)
    assert {ch for ch, _ in c.records} == set(CHANNELS)
    assert len(c.records) == len(original) - 1 and c.skipped_records == 1


def test_version_1_journals_are_still_read(tmp_path: Path) -> None:
    p = tmp_path / "v1.msgpack"
    pk = msgpack.Packer(use_bin_type=True)
    raw = [encode("data", k, k * 1e-3, {"z": 1.0 * k}) for k in range(5)]
    p.write_bytes(pk.pack(["#suscosim-journal", 1, "old"])
                  + b"".join(pk.pack(["plant/state", r, zlib.crc32(r)]) for r in raw))
    c = read_journal(p)
    assert c.run_id == "old" and [r for _, r in c.records] == raw and not c.problem


def test_export_of_a_damaged_journal_writes_alongside_and_exits_2(tmp_path: Path,
                                                                   capsys) -> None:
    p = tmp_path / "journal.msgpack"
    original = _write(p, 100)
    assert cli_main(["export", str(p)]) == 0  # intact: table.csv, exit 0
    good_csv = (tmp_path / "table.csv").read_bytes()
    capsys.readouterr()
    data = bytearray(p.read_bytes())
    data[len(data) // 2] ^= 0x01
    p.write_bytes(bytes(data))
    assert cli_main(["export", str(p)]) == 2
    out, err = capsys.readouterr()
    assert str(p) in err and "1 damaged record(s) skipped" in err and "table.recovered.csv" in err
    assert (tmp_path / "table.csv").read_bytes() == good_csv  # left as it was
    recovered = (tmp_path / "table.recovered.csv").read_text().splitlines()
    assert len(recovered) - 1 == 99  # the step that lost a channel's record, and only it
    import json

    res = json.loads(out)
    assert res["records"] == len(original) - 1 and res["skipped_records"] == 1
    # `suscosim runs` reads it with the same reader: the same counts, and a note.
    (tmp_path / "scenario.json").write_text(json.dumps({"run": {"id": "rel", "n_steps": 99}}))
    info = run_folder.run_info(tmp_path)
    assert info["records"] == res["records"] and info["skipped_records"] == 1
    assert "damaged" in info["error"]


def test_export_never_replaces_a_larger_table(tmp_path: Path, capsys) -> None:
    p = tmp_path / "journal.msgpack"
    _write(p, 100)
    assert cli_main(["export", str(p)]) == 0
    good_csv = (tmp_path / "table.csv").read_bytes()
    _write(p, 10)  # an intact but shorter journal in its place
    assert cli_main(["export", str(p)]) == 2
    err = capsys.readouterr().err
    assert "more rows (100 > 10)" in err
    assert (tmp_path / "table.csv").read_bytes() == good_csv


def test_tail_readers_skip_damage_too(tmp_path: Path) -> None:
    p = tmp_path / "j.msgpack"
    _write(p, 3000)
    data = bytearray(p.read_bytes())
    data[-300] ^= 0xFF  # inside one of the last records
    p.write_bytes(bytes(data))
    assert last_step(p) == 2999
    assert read_journal(p, tail_bytes=4096).skipped_records == 1
