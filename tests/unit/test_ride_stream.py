"""Ride metrics from row batches (#32, nodes/recorder/ride_stream.py, the one implementation)
against the whole-signal ones of tests/unit/ride_oracle.py: the resampling and the jerk
differences bit for bit, SWS exact, the periodogram band RMS, the other RMS and the DTL to
1e-12 relative, Wk to 1e-13 up to 131 s of 500 Hz record (the same impulse response) and 1e-7
beyond; the report's ride section equal to run_metrics within those; traced memory of 5x the
rows within 20 %."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from nodes.recorder import ride_metrics as rm
from nodes.recorder.ride_stream import (
    BandPeriodogram,
    StreamJerk,
    StreamResampler,
    StreamWk,
    streamed_metric_values,
)

from . import ride_oracle as oracle

BAND_REL = 1e-12
WK_SHORT_REL = 1e-13
WK_LONG_REL = 1e-7


def _signal(n: int, fs: float, seed: int = 0, offset: float = 0.0) -> np.ndarray:
    """A ride-like record: 1.2 Hz and 11 Hz tones, a drifting random walk, noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / fs
    walk = np.cumsum(rng.standard_normal(n)) * 0.02
    return (offset + np.sin(2 * np.pi * 1.2 * t) + 0.3 * np.sin(2 * np.pi * 11 * t) + walk
            + 0.1 * rng.standard_normal(n))


def _pieces(x: np.ndarray, rows: int) -> list[np.ndarray]:
    return [x[i:i + rows] for i in range(0, x.size, rows)]


def _rel(a: float, b: float) -> float:
    return abs(a - b) / abs(b)


@pytest.mark.parametrize("fs_in,n,rows", [(1000.0, 10_001, 997), (2000.0, 40_003, 4096),
                                          (1500.0, 9_000, 1), (1000.0, 3_001, 50_000),
                                          (500.0, 2_000, 333), (3000.0, 30_000, 17)])
def test_resampler_equals_resample_poly_bit_for_bit(fs_in, n, rows):
    x = _signal(n, fs_in)
    t = np.arange(n) / fs_in
    want = oracle.resample_to(t, x)
    rs = StreamResampler(n, fs_in)
    got = np.concatenate([*(rs.add(p) for p in _pieces(x, rows)), rs.finish()])
    assert rs.n_out == want.size
    assert np.array_equal(got, want)
    assert np.array_equal(rm.resample_to(t, x), want)  # the product's whole-record call


@pytest.mark.parametrize("n,rows", [(1_501, 700), (50_001, 16_384), (300_000, 65_536)])
def test_band_periodogram_equals_whole_periodogram(n, rows):
    x = _signal(n, 500.0, seed=1, offset=0.7)  # a mean: the periodogram has no detrend
    pg = BandPeriodogram(n, 500.0, 20.0)
    for p in _pieces(x, rows):
        pg.add(p)
    for band in ((0.0, 20.0), (0.0, 16.0), (5.0, 12.5)):
        want = oracle.periodogram_band_rms(x, 500.0, band)
        assert _rel(pg.band_rms(band), want) < BAND_REL
        assert _rel(rm.periodogram_band_rms(x, 500.0, band), want) < BAND_REL
    with pytest.raises(ValueError, match="0 <= f1 < f2"):
        pg.band_rms((3.0, 1.0))


def test_band_periodogram_refuses_an_unfinished_record():
    pg = BandPeriodogram(1000, 500.0, 20.0)
    pg.add(np.ones(999))
    with pytest.raises(ValueError, match="999 samples fed of the 1000"):
        pg.band_rms((0.0, 20.0))


@pytest.mark.parametrize("n,rows,rel", [(4_000, 1_000, WK_SHORT_REL),
                                        (65_536, 16_384, WK_SHORT_REL),
                                        (200_000, 32_768, WK_LONG_REL)])
def test_wk_equals_whole_fft_weighting(n, rows, rel):
    a = _signal(n, 500.0, seed=2)
    wk = StreamWk(n, 500.0)
    for p in _pieces(a, rows):
        wk.add(p)
    assert _rel(wk.rms(), oracle.iso2631_wk_weighted_rms(a, 500.0)) < rel


def test_jerk_equals_gradient():
    a = _signal(10_001, 500.0, seed=3)
    j = StreamJerk(500.0)
    for p in _pieces(a, 1):  # single samples: the ends' and the interior's differences
        j.add(p)
    assert _rel(j.rms(), oracle.rms(oracle.jerk(a, 500.0))) < 1e-13


def _table(n: int, h: float, corners: int = 0, seed: int = 0) -> dict[str, np.ndarray]:
    fs = 1.0 / h
    tab: dict[str, np.ndarray] = {"t": np.arange(n) * h}
    names = ["plant/response/a_b", "plant/response/a_w", "plant/response/a_arm_cg_z",
             "plant/response/alpha_pitch", "plant/state/z_b", "plant/state/z_w",
             "tyre_road/force/F_t", "controller/force/F_d"]
    scale = {"plant/state/z_b": 0.01, "plant/state/z_w": 0.012, "controller/force/F_d": 300}
    for i, name in enumerate(names):
        cols = [name] if corners == 0 else [f"{name}[{c}]" for c in range(corners)]
        for j, col in enumerate(cols):
            tab[col] = scale.get(name, 1.0) * _signal(
                n, fs, seed=seed + 10 * i + j, offset=3000.0 if "F_t" in name else 0.0)
    return tab


def _batches(tab: dict[str, np.ndarray], rows: int):
    def batches(cols):
        cols = list(dict.fromkeys(["t", *cols]))
        for i in range(0, tab["t"].size, rows):
            yield {c: tab[c][i:i + rows] for c in cols}
    return batches


@pytest.mark.parametrize("n,h,corners,rows", [(3_001, 1e-3, 0, 700), (20_000, 5e-4, 4, 4096),
                                              (10_000, 2e-3, 0, 999)])
def test_streamed_metric_values_equal_whole(n, h, corners, rows):
    tab = _table(n, h, corners)
    want = oracle.metric_values(tab)
    got = streamed_metric_values(list(tab), n, _batches(tab, rows))
    assert list(got) == list(want)  # same keys, same order
    for key, (v, unit, label) in want.items():
        g, gu, gl = got[key]
        assert (gu, gl) == (unit, label)
        if key.startswith("sws"):
            assert g == v, key
        else:
            assert _rel(g, v) < (WK_SHORT_REL if "_wk_" in key else BAND_REL), key


def test_streamed_metric_values_bad_time_and_no_channels():
    tab = _table(2_000, 1e-3)
    tab["t"] = tab["t"].copy()
    tab["t"][1500:] += 0.01  # missing steps
    with pytest.raises(ValueError, match="not uniformly sampled"):
        rm.metric_values(tab)
    with pytest.raises(ValueError, match="not uniformly sampled"):
        streamed_metric_values(list(tab), 2_000, _batches(tab, 512))
    bare = {"t": tab["t"], "plant/state/x": tab["plant/state/z_b"]}
    assert streamed_metric_values(list(bare), 2_000, _batches(bare, 512)) == {}


def test_streamed_metric_memory_does_not_grow():
    """5x the rows (the in-band bins grow, 16 B x 0.04 a 500 Hz sample): traced peak
    within 20 %."""
    peaks = []
    for n in (100_000, 500_000):
        tab = _table(n, 1e-3)
        tracemalloc.start()
        streamed_metric_values(list(tab), n, _batches(tab, 65_536))
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    assert peaks[1] < 1.2 * peaks[0], peaks
