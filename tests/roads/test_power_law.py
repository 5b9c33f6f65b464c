"""Thesis Eq. 4.10 power-law roads: PSD level and slope, seeds, correlation, scenario keys."""

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.signal import welch

from cosim.errors import ScenarioError
from nodes.tyre_road.config import build_road

DX = 0.02  # sampling of the road through its public height() interface [m]
BASE = {"type": "power_law", "speed_kmh": 34.0, "length_m": 8000.0, "G": 5e-6, "seed": 11}


def _psd(road, track):
    s = np.arange(0.0, road.length, DX)
    return welch(road.height(s, track), fs=1.0 / DX, nperseg=2 ** 15, detrend="linear")


@pytest.mark.parametrize("G,p", [(1e-7, 2.5), (5e-6, 2.5), (2e-6, 2.0)])
def test_octave_band_variance_matches_G_n_to_the_minus_p(G, p):
    """Independent check: Welch estimate (Hann, averaged) of the sampled road, integrated over
    octaves, against the closed-form integral of G n^-p."""
    road = build_road({**BASE, "G": G, "waviness": p})
    for track in (0, 1):
        n, S = _psd(road, track)
        for lo in (0.05, 0.1, 0.2, 0.4, 0.8):
            hi = 2.0 * lo
            band = (n >= lo) & (n < hi)
            est = np.trapezoid(S[band], n[band])
            exact = quad(lambda u: G * u ** -p, n[band][0], n[band][-1])[0]
            assert est == pytest.approx(exact, rel=0.05), (track, lo)
        fit = (n >= 0.05) & (n <= 2.0)
        slope = np.polyfit(np.log(n[fit]), np.log(S[fit]), 1)[0]
        assert slope == pytest.approx(-p, abs=0.05)


def test_band_limits_the_spectrum():
    road = build_road({**BASE, "band": [0.2, 1.0]})
    n, S = _psd(road, 0)
    inside = S[(n > 0.3) & (n < 0.9)].mean()
    assert S[(n > 1.3) & (n < 2.0)].mean() < 1e-4 * inside
    assert S[(n > 0.02) & (n < 0.12)].mean() < 1e-2 * inside


def test_reproducible_and_seed_dependent():
    cfg = {**BASE, "length_m": 300.0}
    s = np.linspace(0, 300, 5001)
    a = build_road(cfg).height(s, 0)
    assert np.array_equal(a, build_road(cfg).height(s, 0))
    assert not np.allclose(a, build_road({**cfg, "seed": 12}).height(s, 0))
    assert a[0] == 0.0


@pytest.mark.parametrize("corr,lo,hi", [("identical", 0.999, 1.0001),
                                         ("independent", -0.15, 0.15), (0.7, 0.6, 0.8)])
def test_left_right_correlation(corr, lo, hi):
    road = build_road({**BASE, "length_m": 2000.0, "correlation": corr, "band": [0.2, 2.83]})
    s = np.arange(0, 2000, DX)
    r = np.corrcoef(road.height(s, 0), road.height(s, 1))[0, 1]
    assert lo <= r <= hi


@pytest.mark.parametrize("key,value", [
    ("G", -1e-6), ("G", "rough"), ("waviness", 0.0), ("seed", -1), ("seed", 1.5),
    ("correlation", 2.0), ("band", [2.0, 1.0]), ("band", 0.5), ("band", [0.0, 1.0]),
    ("length_m", None), ("gradient", 1.0),
])
def test_bad_keys_name_the_key(key, value):
    cfg = dict(BASE)
    if value is None:
        del cfg[key]
    else:
        cfg[key] = value
    with pytest.raises(ScenarioError, match=rf"road\.{key}"):
        build_road(cfg)


def test_G_is_required():
    cfg = dict(BASE)
    del cfg["G"]
    with pytest.raises(ScenarioError, match=r"road\.G"):
        build_road(cfg)
