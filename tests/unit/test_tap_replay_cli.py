"""``suscosim tap`` / ``replay``: patterns, CSV, counting bad messages, bad input (no bus)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import msgpack
import pytest

from cosim.bus import keyexpr_matches
from cosim.journal import JournalWriter
from cosim.wire import decode, encode
from orchestrator import replay, tap


@pytest.mark.parametrize(("run", "pattern", "expected"), [
    (None, None, "suscosim/*/**"),
    ("r1", None, "suscosim/r1/**"),
    ("r1", "plant/state", "suscosim/r1/plant/state"),
    ("r1", "*/force", "suscosim/r1/*/force"),
    ("r1", "plant/*", "suscosim/r1/plant/*"),
    ("r1", "plant", "suscosim/r1/plant/*"),
    ("*", "**/state", "suscosim/*/**/state"),
])
def test_pattern_to_keyexpr(run, pattern, expected) -> None:
    assert tap.tap_keyexpr(run, pattern) == expected


def test_pattern_matches_the_keys_it_should() -> None:
    kx = tap.tap_keyexpr("r1", "*/force")
    assert keyexpr_matches(kx, "suscosim/r1/tyre_road/force")
    assert keyexpr_matches(kx, "suscosim/r1/controller/force")
    assert not keyexpr_matches(kx, "suscosim/r1/plant/state")
    assert not keyexpr_matches(kx, "suscosim/r2/controller/force")


@pytest.mark.parametrize("pattern", ["a/b/c", "pl$ant", "plant/st ate", "a//b/c"])
def test_bad_patterns_are_refused(pattern) -> None:
    with pytest.raises(tap.TapInputError, match="pattern"):
        tap.tap_keyexpr("r1", pattern)


def test_first_argument_with_a_slash_is_a_pattern_of_every_run(tmp_path: Path) -> None:
    t = tap.resolve_target("plant/state", None, None)
    assert t.keyexpr == "suscosim/*/plant/state" and t.endpoints == [tap.DEFAULT_ENDPOINT]
    with pytest.raises(tap.TapInputError, match="run"):
        tap.resolve_target("bad id!", None, None)


def test_run_folder_gives_run_id_endpoint_and_lowlatency(tmp_path: Path) -> None:
    (tmp_path / "run.json").write_text(json.dumps({
        "run_id": "abc", "endpoints": {"listen": ["tcp/0.0.0.0:7500"],
                                       "connect": ["tcp/10.0.0.1:7447"]},
        "lowlatency": True}))
    t = tap.resolve_target(str(tmp_path), "plant/state", None)
    assert t.keyexpr == "suscosim/abc/plant/state"
    assert t.endpoints == ["tcp/10.0.0.1:7447"] and t.lowlatency  # through the run's router
    (tmp_path / "run.json").write_text(json.dumps({
        "run_id": "abc", "endpoints": {"listen": ["tcp/0.0.0.0:7500"], "connect": []}}))
    t = tap.resolve_target(str(tmp_path), None, None)
    assert t.endpoints == ["tcp/127.0.0.1:7500"] and not t.lowlatency  # to the orchestrator
    # An explicit --connect wins over the recorded endpoints.
    assert tap.resolve_target(str(tmp_path), None, ["tcp/1.2.3.4:1"]).endpoints == \
        ["tcp/1.2.3.4:1"]
    (tmp_path / "run.json").write_text(json.dumps({"run_id": "abc", "mode": "monolithic",
                                                   "endpoints": {"listen": []}}))
    with pytest.raises(tap.TapInputError, match="no endpoint"):
        tap.resolve_target(str(tmp_path), None, None)


def test_tap_counts_bad_messages_and_writes_csv(tmp_path: Path) -> None:
    sink = tap.CsvSink(tmp_path / "t.csv")
    t = tap.Tap("suscosim/r/**", sink)
    key_s, key_f = "suscosim/r/plant/state", "suscosim/r/tyre_road/force"
    foreign = msgpack.packb({"v": 2, "kind": "data", "k": 0, "t": 0.0, "d": {}})
    assert t.handle(key_s, b"\xc1garbage", 0.0) is None
    assert t.handle(key_s, foreign, 0.0) is None
    t.handle(key_s, encode("hello", -1, 0.0, {}), 0.1)  # control: counted, not in the CSV
    for k in range(3):
        t.handle(key_s, encode("data", k, k * 1e-3, {"z_b": 0.1 * k, "v_b": 1.0 / 3}), 0.2)
    t.handle(key_f, encode("data", 0, 0.0, {"F_t": [1.5, 2.5, 3.5, 4.5, 5.5]}), 0.3)
    sink.close()
    assert (t.data, t.control, t.undecodable) == (4, 1, 2)
    assert "unknown schema version 2" in t.last_problem
    assert "2 undecodable" in t.summary() and "4 data" in t.summary()
    assert "undecodable" in t.table(final=True)
    with open(tmp_path / "t.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    # The header grew when the force channel appeared: older rows have empty cells.
    assert list(rows[0]) == ["key", "k", "t", "z_b", "v_b"] + [f"F_t[{i}]" for i in range(5)]
    assert [r["k"] for r in rows] == ["0", "1", "2", "0"]
    assert float(rows[1]["v_b"]) == 1.0 / 3 and rows[1]["F_t[0]"] == ""
    assert rows[3]["key"] == key_f and float(rows[3]["F_t[4]"]) == 5.5
    # Appending to an existing tap CSV keeps its header; a foreign CSV is refused.
    sink = tap.CsvSink(tmp_path / "t.csv")
    assert sink.columns[:5] == ["key", "k", "t", "z_b", "v_b"]
    sink.close()
    (tmp_path / "other.csv").write_text("a,b\n1,2\n")
    with pytest.raises(tap.TapInputError, match="not a tap CSV"):
        tap.CsvSink(tmp_path / "other.csv")


def test_values_are_shortened() -> None:
    assert tap.fmt_value(0.123456789) == "0.12346"
    assert tap.fmt_value([1.0, 2.0, 3.0, 4.0]) == "[1, 2, 3, 4]"
    assert tap.fmt_value(list(range(10))) == "[0, 1, 2, ...](10)"


def test_tap_cli_bad_input_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert tap.main(["r1", "a/b/c"]) == 2
    assert "pattern" in capsys.readouterr().err
    assert tap.main(["r1", "--count", "0"]) == 2
    assert "--count" in capsys.readouterr().err
    assert tap.main(["r1", "--duration", "-1"]) == 2
    (tmp_path / "x.csv").write_text("hello\n")
    assert tap.main(["r1", "--csv", str(tmp_path / "x.csv")]) == 2
    assert "not a tap CSV" in capsys.readouterr().err
    empty = tmp_path / "empty_dir"
    empty.mkdir()
    assert tap.main([str(empty)]) == 2
    assert "not a run folder" in capsys.readouterr().err


def _journal(path: Path, run_id: str, n: int) -> None:
    w = JournalWriter(path, run_id)
    for k in range(n):
        w.append("plant/state", encode("data", k, k * 1e-3, {"z_b": float(k)}))
        w.append("tyre_road/force", encode("data", k, k * 1e-3, {"F_t": 1.0}))
    w.close()


def test_replay_loads_a_journal_or_a_run_folder(tmp_path: Path) -> None:
    _journal(tmp_path / "journal.msgpack", "orig", 5)
    for where in (tmp_path, tmp_path / "journal.msgpack"):
        rec = replay.Recorded(where)
        records = list(rec)
        assert rec.run_id == "orig" and rec.skipped == 0 and rec.problem == ""
        assert len(rec) == 10 and rec.channels == {("plant", "state"), ("tyre_road", "force")}
        assert [(n, c) for n, c, _r, _t in records[:2]] == [("plant", "state"),
                                                             ("tyre_road", "force")]
        assert [t for *_x, t in records[::2]] == [k * 1e-3 for k in range(5)]
        assert decode(records[-2][2]).d == {"z_b": 4.0}


class _FakeBus:
    """Records what is published (the replay logic without a network)."""

    def __init__(self) -> None:
        self.sent: list[tuple[str, bytes]] = []

    def publisher(self, key: str):
        return lambda raw: self.sent.append((key, raw))


def test_replay_publishes_every_record_under_the_new_run_id(tmp_path: Path) -> None:
    _journal(tmp_path / "journal.msgpack", "orig", 4)
    recorded = replay.Recorded(tmp_path)
    records = list(recorded)
    bus = _FakeBus()
    sent, _wall = replay.replay(bus, "orig-replay", recorded, speed=None, wait_s=0)

    assert sent == 8 == len(bus.sent)
    assert [k for k, _ in bus.sent[:2]] == ["suscosim/orig-replay/plant/state",
                                            "suscosim/orig-replay/tyre_road/force"]
    assert [raw for _, raw in bus.sent] == [r[2] for r in records]  # the bytes, untouched


def test_replay_cli_bad_input_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert replay.main([str(tmp_path / "nope.msgpack")]) == 2
    assert "no such journal" in capsys.readouterr().err
    (tmp_path / "j.msgpack").write_bytes(b"not a journal at all")
    assert replay.main([str(tmp_path / "j.msgpack")]) == 2
    assert "not a suscosim journal" in capsys.readouterr().err
    _journal(tmp_path / "empty.msgpack", "orig", 0)
    assert replay.main([str(tmp_path / "empty.msgpack")]) == 2
    assert "no data message" in capsys.readouterr().err
    _journal(tmp_path / "ok.msgpack", "orig", 2)
    assert replay.main([str(tmp_path / "ok.msgpack"), "--run", "a/b"]) == 2
    assert "run id" in capsys.readouterr().err
    assert replay.main([str(tmp_path / "ok.msgpack"), "--speed", "0"]) == 2
    assert replay.main([str(tmp_path / "ok.msgpack"), "--fast", "--speed", "2"]) == 2


def test_raw_mode_prints_one_line_per_message() -> None:
    import io

    out = io.StringIO()
    t = tap.Tap("suscosim/r/**", raw=True, out=out)
    t.handle("suscosim/r/plant/state", encode("data", 7, 0.007, {"z_b": 0.5}), 0.0)
    t.handle("suscosim/r/plant/state", b"\xc1", 0.0)
    lines = out.getvalue().splitlines()
    assert lines[0] == 'r/plant/state data k=7 t=0.007 {"z_b":0.5}'
    assert lines[1].startswith("r/plant/state UNDECODABLE (not msgpack")


def test_session_mode_client_unless_listening() -> None:
    assert tap.is_loopback("tcp/127.0.0.1:7447") and tap.is_loopback("tcp/localhost:1")
    assert tap.is_loopback("tcp/[::1]:7447") and not tap.is_loopback("tcp/10.0.0.1:7447")
    assert not tap.is_loopback("tls/router.example.org:7447")
    # a run's local nodes are an explicit mesh: on loopback too, a tap is the orchestrator's
    # client (a peer connected to it would hear none of them)
    assert tap.session_mode("auto", ["tcp/127.0.0.1:7447"], None) == "client"
    assert tap.session_mode("auto", ["tcp/10.0.0.1:7447"], None) == "client"
    assert tap.session_mode("auto", ["tcp/10.0.0.1:7447"], ["tcp/0.0.0.0:7000"]) == "peer"
    assert tap.session_mode("peer", ["tcp/10.0.0.1:7447"], None) == "peer"
    assert tap.session_mode("client", ["tcp/127.0.0.1:7447"], None) == "client"
