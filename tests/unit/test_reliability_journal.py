"""#15 item 1, #32: a damaged segment costs that segment only, the records lost are counted
exactly (#30 item 15), and every reader agrees (synthetic journals; the real-run version is
tests/integration/test_reliability_journal.py)."""

from __future__ import annotations

from pathlib import Path

import msgpack
import pytest

from cosim import run_folder
from cosim.errors import InputFileError
from cosim.journal import JournalWriter, last_step, read_journal
from cosim.wire import encode
from orchestrator.export import main as export_main

CHANNELS = ("plant/state", "tyre_road/force")


def _write(path: Path, n: int, every: int = 2) -> list[tuple[str, bytes]]:
    """``n`` steps of two channels, a segment every ``every`` steps."""
    w = JournalWriter(path, "rel")
    records = []
    for k in range(n):
        for ch in CHANNELS:
            raw = encode("data", k, k * 1e-3, {"z": 0.001 * k, "F": [1.0 * k, -2.0 * k]})
            w.append(ch, raw)
            records.append((ch, raw))
        if (k + 1) % every == 0:
            w.flush()
    w.close()
    return records


def _header_len(path: Path) -> int:
    u = msgpack.Unpacker()
    u.feed(path.read_bytes())
    next(u)
    return u.tell()


def test_every_single_byte_flip_costs_one_segment_at_most_counted_exactly(
        tmp_path: Path) -> None:
    """Flip each byte after the header in turn: the reader keeps every record but
    those of the one segment hit (2 steps, 4 records here), in order, and says it lost 4."""
    p = tmp_path / "j.msgpack"
    original = _write(p, 6, every=2)
    clean = p.read_bytes()
    per_segment = 2 * len(CHANNELS)
    for i in range(_header_len(p), len(clean)):
        data = bytearray(clean)
        data[i] ^= 0x5A
        p.write_bytes(bytes(data))
        c = read_journal(p)
        kept = c.records
        assert len(kept) == len(original) - per_segment, (i, c.problem)
        idx = [original.index(r) for r in kept]
        assert idx == sorted(idx), i  # in order, nothing forged by the damage
        lost = sorted(set(range(len(original))) - set(idx))
        assert lost == list(range(lost[0], lost[0] + per_segment)), i  # one whole segment
        if c.torn:  # the last segment hit: a torn tail, its records counted from its header
            assert lost[-1] == len(original) - 1 and c.torn_records in (per_segment, None), i
        else:
            assert c.skipped_records == per_segment, (i, c.problem)


def test_4_kib_of_zeros_count_what_they_cost(tmp_path: Path) -> None:
    """#30 item 15: 4 KiB of zeros over a journal reported "1 damaged record" when 41 were
    lost. They are counted from the segments around (exact)."""
    p = tmp_path / "j.msgpack"
    original = _write(p, 400, every=5)
    data = bytearray(p.read_bytes())
    data[len(data) // 3:len(data) // 3 + 4096] = bytes(4096)
    p.write_bytes(bytes(data))
    c = read_journal(p)
    assert c.skipped_records == len(original) - len(c.records) > 40
    assert f"{c.skipped_records} damaged record(s) skipped" in c.problem
    assert "estimated" not in c.problem


def test_journals_of_versions_1_and_2_are_refused_naming_the_version(tmp_path: Path) -> None:
    pk = msgpack.Packer(use_bin_type=True)
    for version in (1, 2):
        p = tmp_path / f"v{version}.msgpack"
        raw = encode("data", 0, 0.0, {"z": 1.0})
        p.write_bytes(pk.pack(["#suscosim-journal", version, "old"])
                      + pk.pack(["plant/state", raw, 0]))
        with pytest.raises(InputFileError, match=f"journal version {version} not supported "
                                                 r"\(this reader takes 3\)"):
            read_journal(p)


def test_export_of_a_damaged_journal_writes_alongside_and_exits_2(tmp_path: Path,
                                                                   capsys) -> None:
    p = tmp_path / "journal.msgpack"
    original = _write(p, 100, every=1)  # a segment a step
    assert export_main([str(p)]) == 0  # intact: table.csv, exit 0
    good_csv = (tmp_path / "table.csv").read_bytes()
    capsys.readouterr()
    data = bytearray(p.read_bytes())
    data[len(data) // 2] ^= 0x01
    p.write_bytes(bytes(data))
    assert export_main([str(p)]) == 2
    out, err = capsys.readouterr()
    assert str(p) in err and "2 damaged record(s) skipped" in err and "table.recovered.csv" in err
    assert (tmp_path / "table.csv").read_bytes() == good_csv  # left as it was
    recovered = (tmp_path / "table.recovered.csv").read_text().splitlines()
    assert len(recovered) - 1 == 99  # the step of the damaged segment, and only it
    import json

    res = json.loads(out)
    assert res["records"] == len(original) - 2 and res["skipped_records"] == 2
    # `suscosim runs` reads it with the same reader: the same counts, and a note.
    (tmp_path / "scenario.json").write_text(json.dumps({"run": {"id": "rel", "n_steps": 99}}))
    info = run_folder.run_info(tmp_path)
    assert info["records"] == res["records"] and info["skipped_records"] == 2
    assert "damaged" in info["error"]


def test_export_never_replaces_a_larger_table(tmp_path: Path, capsys) -> None:
    p = tmp_path / "journal.msgpack"
    _write(p, 100)
    assert export_main([str(p)]) == 0
    good_csv = (tmp_path / "table.csv").read_bytes()
    _write(p, 10)  # an intact but shorter journal in its place
    assert export_main([str(p)]) == 2
    err = capsys.readouterr().err
    assert "more rows (100 > 10)" in err
    assert (tmp_path / "table.csv").read_bytes() == good_csv


def test_tail_readers_skip_damage_too(tmp_path: Path) -> None:
    p3 = tmp_path / "j3.msgpack"
    _write(p3, 3000, every=10)
    data = bytearray(p3.read_bytes())
    data[-30] ^= 0xFF  # inside the last segment's body: steps 2990-2999 are lost
    p3.write_bytes(bytes(data))
    assert last_step(p3) == 2989
    c = read_journal(p3, tail_bytes=4096)
    assert c.skipped_records == 20 and not c.torn and 0 < len(c.records) < 6000
