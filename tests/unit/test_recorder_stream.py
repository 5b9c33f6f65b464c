"""The recorder run for real on the in-memory bus, fed a synthetic stream in-process:
#30 item 12 (a replayed records batch is counted, not journaled) and #32 (its memory per
coupled step does not grow with the run; its table is the journal's, bit for bit)."""

from __future__ import annotations

import math
import queue
import threading
import time
import tracemalloc
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cosim import keys
from cosim.journal import last_step, read_journal
from cosim.participant import Participant
from cosim.table import read_table
from cosim.wire import decode, encode
from tests.memory_bus import MemoryBus
from tests.table_oracle import build_table

H = 1e-3


class Recorder:
    """The recorder node's ``run`` in a thread, a plant's records feed and the clock."""

    def __init__(self, tmp_path: Path, n: int) -> None:
        self.bus = MemoryBus()
        self.bus.token(keys.key("r", keys.ORCHESTRATOR, keys.ALIVE))
        self.n, self.dir = n, tmp_path
        scenario = {"run": {"dir": str(tmp_path), "nodes": ["plant", "recorder"], "h": H,
                            "start_timeout_s": 10.0, "stall_timeout_s": 30.0, "n_steps": n}}
        self.part = Participant(self.bus, "r", "recorder")
        self.errors: queue.SimpleQueue[BaseException] = queue.SimpleQueue()
        self.ctl: list[Any] = []
        self.bus.subscribe(keys.key("r", "recorder", keys.CTL),
                           lambda _k, raw: self.ctl.append(decode(raw)))
        from nodes.recorder import node as recorder

        def body() -> None:
            try:
                recorder.run(self.part, scenario)
            except BaseException as exc:  # noqa: BLE001 - asserted by the tests
                self.errors.put(exc)

        self.thread = threading.Thread(target=body, daemon=True)
        self.thread.start()
        self.records = keys.key("r", "plant", keys.RECORDS)
        self.clock = keys.key("r", keys.ORCHESTRATOR, keys.CLOCK)
        deadline = time.monotonic() + 10
        while not self.kinds("ready") and time.monotonic() < deadline:
            self.bus.put(self.records, encode("hello", -1, 0.0, {}))
            time.sleep(0.02)
        self.bus.put(self.clock, encode("start", -1, 0.0, {
            "n_steps": n, "h": H,
            "info": {"plant": {"outputs": ["state", "arm"]}, "recorder": {}}}))

    def kinds(self, kind: str) -> list[Any]:
        return [m for m in self.ctl if m.kind == kind]

    @staticmethod
    def batch(k0: int, k1: int) -> bytes:
        """One records batch of steps k0..k1-1: two channels, 4 + 6 values a step."""
        recs = []
        for k in range(k0, k1):
            x = np.sin(0.37 * k)
            recs.append(["state", encode("data", k, k * H, {
                "z_b": x, "v_b": x * 0.5, "z_w": -x, "v_w": k * 1e-7})])
            recs.append(["arm", encode("data", k, k * H, {
                "F": [x, 2 * x, 3 * x], "M": [1.0, -x, float(k)]})])
        return encode("records", k1 - 1, (k1 - 1) * H, {"records": recs})

    def wait_step(self, k: int, timeout: float = 60.0) -> None:
        deadline = time.monotonic() + timeout
        while (last_step(self.dir / "journal.msgpack") or -1) < k:
            assert time.monotonic() < deadline, f"the recorder did not reach step {k}"
            assert self.thread.is_alive(), self.errors.get()
            time.sleep(0.02)

    def finish(self) -> dict[str, Any]:
        deadline = time.monotonic() + 60
        while not self.kinds("done") and time.monotonic() < deadline and \
                self.thread.is_alive():
            time.sleep(0.02)
        self.bus.put(self.clock, encode("done", self.n, self.n * H, {}))
        self.thread.join(timeout=30)
        assert self.errors.empty(), self.errors.get()
        (done,) = self.kinds("done")
        self.part.close()
        return dict(done.d)


def test_a_replayed_records_batch_is_counted_not_journaled(tmp_path: Path) -> None:
    """#30 item 12: captured signed batches replayed into the same run wrote 126 MB of
    journal in 8 s, nothing counted. Every step replayed 5 times here: the journal holds each
    record once, and the duplicates are counted (as rejected too)."""
    n = 400
    rec = Recorder(tmp_path, n)
    batches = [rec.batch(k, min(k + 20, n + 1)) for k in range(0, n + 1, 20)]
    for b in batches[:-1]:
        rec.bus.put(rec.records, b)
    for _ in range(5):  # the replay, before the run's last batch
        for b in batches[:-1]:
            rec.bus.put(rec.records, b)
    rec.bus.put(rec.records, batches[-1])
    done = rec.finish()
    journal = read_journal(tmp_path / "journal.msgpack")
    assert len(journal.records) == 2 * (n + 1)  # every record once
    assert done["duplicates"] == 5 * 2 * n and done["rejected"] == done["duplicates"]
    assert done["rows"] == n + 1


@pytest.mark.long  # memory growth: 12 000 steps under tracemalloc
def test_recorder_memory_per_step_is_bounded_and_its_table_is_the_journals(
        tmp_path: Path, monkeypatch) -> None:
    """#32: the recorder grew ~3.5 kB a coupled step (a set of every step per channel, the
    table rebuilt from the whole journal). Python's traced memory between step 4096 and
    step 10 240 (of 12 000) grows by less than 20 B a step here (its fixed buffers: a
    Parquet row group and a chunk of 1024 rows, both written out at both marks, and a
    journal segment). The table the
    recorder wrote as it went is the one rebuilt from its journal, bit for bit."""
    monkeypatch.setattr("cosim.table_writer.GROUP_ROWS", 1024)
    monkeypatch.setattr("cosim.table_writer.CHUNK_ROWS", 1024)
    n = 12_000
    rec = Recorder(tmp_path, n)
    tracemalloc.start()
    try:
        marks: dict[int, int] = {}
        k = 0
        for mark in (4096, 10_240, n + 1):  # whole chunks written: no row held
            while k < mark:
                rec.bus.put(rec.records, rec.batch(k, min(k + 50, mark)))
                k = min(k + 50, mark)
                if k % 1000 == 0:  # do not run far ahead of the recorder (a bus queue)
                    rec.wait_step(k - 1)
            rec.wait_step(mark - 1)
            marks[mark] = tracemalloc.get_traced_memory()[0]
        done = rec.finish()
    finally:
        tracemalloc.stop()
    per_step = (marks[10_240] - marks[4096]) / (10_240 - 4096)
    print(f"traced memory: {per_step:.1f} B a step")
    assert per_step < 20, f"{per_step:.0f} B a step"
    assert done["rows"] == n + 1 and done["duplicates"] == 0
    rebuilt, bad = build_table(read_journal(tmp_path / "journal.msgpack").records)
    written = read_table(tmp_path / "table.parquet")
    assert bad == 0 and list(written) == list(rebuilt)
    for col, x in rebuilt.items():
        assert written[col].dtype == x.dtype and written[col].tobytes() == x.tobytes(), col
    stats = done["stats"]["plant/arm/M[2]"]
    assert stats["max"] == n and stats["mean"] == n / 2  # sum of 0..n, exact in floats


def test_implausible_messages_of_a_signed_records_batch_are_rejected_not_journaled(
        tmp_path: Path) -> None:
    """#30 item 14: NaN / 1e308 / negative-time data from an insider, in a batch that
    verifies, is rejected and counted by the recorder (each message checked against its
    channel's schema as it is decoded, cosim/schema.py); the journal and the table hold only
    the plausible messages of the same batch."""
    n = 40
    rec = Recorder(tmp_path, n)
    good = decode(rec.batch(0, n + 1)).d["records"]
    bad = [["state", encode("data", 5, 5 * H, {"z_b": math.nan, "v_b": 0.0, "z_w": 0.0,
                                                "v_w": 0.0})],
           ["state", encode("data", 6, 6 * H, {"z_b": 1e308, "v_b": 0.0, "z_w": 0.0,
                                                "v_w": 0.0})],
           ["state", encode("data", 7, -7 * H, {"z_b": 0.0, "v_b": 0.0, "z_w": 0.0,
                                                 "v_w": 0.0})]]
    rec.bus.put(rec.records, encode("records", n, n * H, {"records": bad + good}))
    done = rec.finish()
    journal = read_journal(tmp_path / "journal.msgpack")
    assert len(journal.records) == 2 * (n + 1)
    assert [raw for _, raw in journal.records] == [raw for _, raw in good]
    assert done["rejected"] == 3 and done["rows"] == n + 1


def test_a_lost_records_batch_ends_the_run_naming_its_steps_and_the_journal_stays_readable(
        tmp_path: Path) -> None:
    """#28 follow-up: a sweep's recorder once never got plant steps 65-96 (one records batch
    lost between the plant and the recorder) and waited for the 30 s stall timeout, saying
    only "incomplete". Here the batch of steps 20-39 never comes: the recorder ends with an
    error naming the channels' missing steps and the producer, as soon as the next batch
    shows the hole, and what it journaled (steps 0-19 and the batch after the hole) reads."""
    n = 100
    rec = Recorder(tmp_path, n)
    for k0 in (0, 40, 60):  # 20..39 lost
        rec.bus.put(rec.records, rec.batch(k0, k0 + 20))
    rec.thread.join(timeout=25)  # without the check: "no data for 10.0 s; incomplete: ..."
    assert not rec.thread.is_alive(), "the recorder waited on instead of naming the hole"
    err = rec.errors.get_nowait()
    assert "plant/state steps 20-39 never arrived" in str(err) and "'plant'" in str(err)
    journal = read_journal(tmp_path / "journal.msgpack")
    steps = sorted({decode(raw).k for name, raw in journal.records if name == "plant/state"})
    assert steps[:20] == list(range(20)) and 20 not in steps
    rec.part.close()
