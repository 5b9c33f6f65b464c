"""cosim.table_writer: the table written as rows complete equals build_table's, bit for bit,
for streams with holes, duplicates, a stray message, channels lagging one another, and in
chunks and row groups smaller than the run."""

from __future__ import annotations

import random

import numpy as np

from cosim.table import channel_stats, read_table
from cosim.table_writer import TableWriter, journal_table, table_of_journal
from cosim.wire import encode
from tests.table_oracle import build_table


def _stream(seed: int, n: int = 3000) -> list[tuple[str, bytes]]:
    """Three channels, each in its own order; interleaved with lags of up to 40 steps; some
    steps missing in one channel, some sent twice, one stray message of another layout."""
    rng = random.Random(seed)
    per = {}
    for ch in ("plant/state", "tyre_road/force", "controller/force"):
        recs = []
        for k in range(n):
            if rng.random() < 0.01:
                continue  # a hole: that step is no row
            d = {"z": rng.gauss(0, 1), "v": [rng.random(), -rng.random()]}
            recs.append((ch, encode("data", k, k * 1e-3, d)))
            if rng.random() < 0.01:
                recs.append((ch, encode("data", k, k * 1e-3, {"z": 9.0, "v": [9.0, 9.0]})))
        per[ch] = recs
    per["plant/state"].insert(5, ("plant/state", encode("data", 5, 0.005, {"z": [1.0]})))
    out, idx = [], dict.fromkeys(per, 0)
    while any(idx[c] < len(per[c]) for c in per):
        c = rng.choice([c for c in per if idx[c] < len(per[c])])
        take = rng.randint(1, 40)
        out += per[c][idx[c]:idx[c] + take]
        idx[c] += take
    return out


def test_streamed_table_equals_journal_table(tmp_path) -> None:
    for seed in range(3):
        records = _stream(seed)
        ref, bad_ref = build_table(records)
        writer, bad = table_of_journal(lambda r=records: r, tmp_path, chunk_rows=256)
        assert writer is not None
        writer.group_rows = 700
        files = writer.close()
        got = read_table(files["parquet"])
        assert list(got) == list(ref) and bad == bad_ref, seed
        for col, x in ref.items():
            assert got[col].dtype == x.dtype and got[col].tobytes() == x.tobytes(), (seed, col)
        csv = read_table(files["csv"])
        mem, bad_mem = journal_table(records)  # the same table, held in memory
        assert list(mem) == list(ref) and bad_mem == bad_ref, seed
        for col, x in ref.items():
            np.testing.assert_array_equal(csv[col], x)
            assert mem[col].dtype == x.dtype and mem[col].tobytes() == x.tobytes(), (seed, col)
        st, st_ref = writer.stats(), channel_stats(ref)
        for col in st_ref:
            for q in ("max", "min", "peak", "t_peak"):
                assert st[col][q] == st_ref[col][q], (col, q)
            for q in ("mean", "rms", "std"):
                assert abs(st[col][q] - st_ref[col][q]) <= 1e-12 * max(1.0, abs(st_ref[col][q]))


def test_a_step_behind_the_last_row_is_taken_and_counted_late() -> None:
    w = TableWriter(["a/x", "b/y"], None)
    for k in (0, 1, 2):
        assert w.add("a/x", k, k * 1.0, {"v": 1.0}) is None
    assert w.add("b/y", 0, 0.0, {"v": 2.0}) is None
    assert w.add("b/y", 2, 2.0, {"v": 2.0}) is None  # row 2 written: step 1 can no longer be
    assert w.add("b/y", 1, 1.0, {"v": 2.0}) is None and w.late == 1
    assert w.add("b/y", 3, 3.0, {"v": [2.0]}) is not None  # another layout: left out, why
    w.close()
    assert w.rows == 2 and w.held == 0


def test_a_column_with_nan_has_nan_stats_as_numpy_gives() -> None:
    """A NaN anywhere in a column (a law's extra field may be NaN) makes its max, min,
    mean, rms and std NaN, as channel_stats (numpy) gives, in whichever chunk it comes."""
    for at in (3, 600):
        records = [("controller/force", encode("data", k, k * 1e-3,
                                               {"F": float("nan") if k == at else k * 0.5}))
                   for k in range(1000)]
        writer, _ = table_of_journal(lambda r=records: r, None, chunk_rows=256)
        assert writer is not None
        ref, _ = build_table(records)
        st, st_ref = writer.stats()["controller/force/F"], channel_stats(ref)[
            "controller/force/F"]
        for q in ("max", "min", "mean", "rms", "std"):
            assert np.isnan(st_ref[q]) and np.isnan(st[q]), (at, q, st[q])
