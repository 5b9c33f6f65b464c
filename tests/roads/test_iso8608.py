"""ISO 8608 random roads: PSD slope and level of the class, reproducibility, correlation."""

import numpy as np
import pytest
from scipy.signal import welch

from nodes.tyre_road.config import build_road
from nodes.tyre_road.iso8608 import GD_N0

DX = 0.02  # sampling of the road through its public height() interface [m]
N_LO, N_HI = 0.05, 2.0  # band of the check [cycles/m], inside the generated 0.011-2.83


def _fit(road, track):
    s = np.arange(0.0, road.length, DX)
    z = road.height(s, track)
    n, G = welch(z, fs=1.0 / DX, nperseg=2 ** 14, detrend="linear")
    band = (n >= N_LO) & (n <= N_HI)
    slope, icpt = np.polyfit(np.log10(n[band] / 0.1), np.log10(G[band]), 1)
    return slope, 10 ** icpt


@pytest.mark.parametrize("cls", ["A", "C", "E", "H"])
def test_psd_slope_and_level_match_the_class(cls):
    road = build_road({"type": "iso8608", "speed_kmh": 34, "length_m": 2000.0,
                       "class": cls, "seed": 7})
    for track in (0, 1):
        slope, gd_n0 = _fit(road, track)
        assert slope == pytest.approx(-2.0, abs=0.1)
        assert gd_n0 == pytest.approx(GD_N0[cls], rel=0.15)


def test_reproducible_and_seed_dependent():
    cfg = {"type": "iso8608", "speed_kmh": 34, "length_m": 300.0, "class": "C", "seed": 1}
    s = np.linspace(0, 300, 5001)
    a = build_road(cfg).height(s, 0)
    b = build_road(cfg).height(s, 0)
    c = build_road({**cfg, "seed": 2}).height(s, 0)
    assert np.array_equal(a, b)
    assert not np.allclose(a, c)
    assert a[0] == 0.0


@pytest.mark.parametrize("corr,lo,hi", [("identical", 0.999, 1.0001),
                                         ("independent", -0.15, 0.15), (0.7, 0.6, 0.8)])
def test_left_right_correlation(corr, lo, hi):
    road = build_road({"type": "iso8608", "speed_kmh": 34, "length_m": 2000.0,
                       "class": "D", "seed": 3, "correlation": corr,
                       "n_min": 0.2, "n_max": 2.83})  # high-pass: many independent lines
    s = np.arange(0, 2000, DX)
    r = np.corrcoef(road.height(s, 0), road.height(s, 1))[0, 1]
    assert lo <= r <= hi
