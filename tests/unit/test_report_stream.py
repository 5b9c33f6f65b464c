"""The report's streamed table (#32): decimation, Welch PSD, statistics and ride metrics from
row batches equal the whole-table computations (the ride metrics to 1e-12 relative); the
traced memory of a pass does not grow with the table."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from scipy.signal import welch

from cosim.table import channel_stats
from nodes.recorder.ride_metrics import run_metrics
from orchestrator.report.plots import decimate
from orchestrator.report.run_page import streamed_panels, streamed_ride_metrics
from orchestrator.report.signals import time_history_panels
from orchestrator.report.stream import (
    StreamDecimator,
    StreamWelch,
    TableSource,
    column_stats,
    psd_nperseg,
)


def _table(n: int, seed: int = 0) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 1e-3
    zb = np.cumsum(rng.normal(size=n)) * 1e-5
    return {"k": np.arange(n, dtype=float), "t": t,
            "plant/state/z_b": zb, "plant/state/z_w": zb + rng.normal(size=n) * 1e-3,
            "plant/response/a_b": rng.normal(size=n),
            "plant/response/a_w": 10 * rng.normal(size=n),
            "tyre_road/force/F_t": 4000 + 300 * rng.normal(size=n),
            "controller/force/F_d": 200 * rng.normal(size=n)}


def _parquet(tmp_path, table, group=16384):
    p = tmp_path / f"table-{len(table['t'])}.parquet"
    w = None
    names = list(table)
    for i in range(0, len(table["t"]), group):
        tab = pa.table({c: table[c][i:i + group] for c in names})
        w = w or pq.ParquetWriter(p, tab.schema)
        w.write_table(tab)
    assert w is not None
    w.close()
    return p


@pytest.mark.parametrize("n,rows", [(3000, 700), (10_007, 997), (123_457, 65_536)])
def test_decimator_equals_decimate(n, rows):
    rng = np.random.default_rng(n)
    x = rng.normal(size=n)
    x[rng.integers(0, n, 40)] = np.nan
    x[100:900] = np.nan  # all-NaN buckets stay gaps
    t = np.arange(n) * 1e-3
    d = StreamDecimator(n, 4000)
    for i in range(0, n, rows):
        d.add(t[i:i + rows], x[i:i + rows])
    want, got = decimate(t, x), d.result()
    assert np.array_equal(want[0], got[0])
    assert np.array_equal(want[1], got[1], equal_nan=True)


def test_welch_from_batches_equals_scipy():
    x = np.random.default_rng(1).normal(size=100_003)
    nps = psd_nperseg(x.size)
    f, p = welch(x, fs=1000.0, nperseg=nps, detrend="constant")
    w = StreamWelch(1000.0, nps)
    for i in range(0, x.size, 6553):
        w.add(x[i:i + 6553])
    f2, p2 = w.result()
    assert np.array_equal(f, f2)
    np.testing.assert_allclose(p2, p, rtol=1e-12, atol=0)
    assert psd_nperseg(10**7) == 32_768  # capped: one segment held, not n/4


def test_stats_panels_ride_from_batches_equal_whole(tmp_path):
    table = _table(40_000)
    src = TableSource(path=_parquet(tmp_path, table))
    assert src.n_rows == 40_000
    whole = channel_stats({c: v for c, v in table.items() if c != "k"})
    got = column_stats(src)
    assert set(got) == set(whole)
    for c, st in whole.items():
        for k in ("max", "min", "peak", "t_peak"):
            assert got[c][k] == st[k], (c, k)
        for k in ("mean", "rms", "std"):
            assert got[c][k] == pytest.approx(st[k], rel=1e-12, abs=1e-15), (c, k)
    panels, _missing, (t0, t1) = streamed_panels(src, time_history_panels)
    want, _ = time_history_panels({c: v for c, v in table.items() if c != "k"})
    assert (t0, t1) == (table["t"][0], table["t"][-1])
    for (title, _u, lines), (title2, _u2, lines2) in zip(panels, want, strict=True):
        assert title == title2
        for (_l, (tt, yy)), (_l2, y) in zip(lines, lines2, strict=True):
            wt, wy = decimate(table["t"], y)
            assert np.array_equal(tt, wt) and np.array_equal(yy, wy)
    ride, want = streamed_ride_metrics(src), run_metrics(table)
    assert list(ride) == list(want)  # nodes/recorder/ride_stream.py: to rounding
    for k, v in want.items():
        assert ride[k] == pytest.approx(v, rel=1e-12), k


def test_pass_memory_does_not_grow(tmp_path):
    """Statistics and decimated panels of 5x the rows: traced peak within 20 %."""
    peaks = []
    for n in (60_000, 300_000):
        src = TableSource(path=_parquet(tmp_path, _table(n)))
        tracemalloc.start()
        column_stats(src)
        streamed_panels(src, time_history_panels)
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    assert peaks[1] < 1.2 * peaks[0], peaks
