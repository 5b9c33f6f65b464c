"""#32 item 3: a long history is plotted as min/max per bucket, every peak kept -- the last,
shorter bucket's too (it was dropped), and around a NaN."""

from __future__ import annotations

import numpy as np

from orchestrator.report.plots import MAX_PLOT_POINTS, decimate


def test_a_million_samples_become_a_plot_that_keeps_every_peak() -> None:
    n = 1_000_003
    t = np.arange(n) * 1e-3
    x = np.sin(2 * np.pi * 0.37 * t)
    x[-1], x[500_001], x[17] = 5.0, -7.0, np.nan
    x[18] = 3.0
    tt, xx = decimate(t, x)
    assert len(tt) <= MAX_PLOT_POINTS and np.all(np.diff(tt) >= 0)
    assert np.nanmax(xx) == 5.0 and tt[np.nanargmax(xx)] == t[-1]  # the last sample's peak
    assert np.nanmin(xx) == -7.0 and tt[np.nanargmin(xx)] == t[500_001]
    assert 3.0 in xx  # beside a NaN
    # every bucket's extremes: the envelope of the plot is the signal's
    b = int(np.ceil(n / (MAX_PLOT_POINTS // 2)))
    full = x[: (n // b) * b].reshape(-1, b)
    np.testing.assert_array_equal(np.nanmax(xx[: 2 * full.shape[0]].reshape(-1, 2), axis=1),
                                  np.nanmax(full, axis=1))
