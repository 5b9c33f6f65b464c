"""Appendix II log decrement: round trip on a known SDOF, and the command on the corner."""

import numpy as np
import pytest

from nodes.plant.double_wishbone import DoubleWishboneParams
from nodes.plant.equivalent_lumped import identify, log_decrement


def test_round_trip_on_the_table_4_3_sdof():
    m, k, c = 535.0, 31000.0, 1500.0
    wn = np.sqrt(k / m)
    zeta = c / (2 * np.sqrt(k * m))
    wd = wn * np.sqrt(1 - zeta ** 2)
    t = np.arange(0, 5, 1e-3)
    x = 0.01 * np.exp(-zeta * wn * t) * np.cos(wd * t)
    ld = log_decrement(t, x)
    assert ld["zeta"] == pytest.approx(0.184, abs=0.002)
    assert m * ld["omega_n"] ** 2 == pytest.approx(k, rel=0.01)
    assert ld["zeta"] * 2 * np.sqrt(m * ld["omega_n"] ** 2 * m) == pytest.approx(c, rel=0.02)
    assert np.exp(ld["delta"]) == pytest.approx(3.25, abs=0.05)


def test_identify_on_the_realistic_corner():
    eq = identify(step=0.01, dt=2e-3, t_end=3.0)
    assert eq["m_w"] == pytest.approx(47.75)
    # wheel rate of a torsion bar on the 0.37 m lower arm: K_theta / 0.37^2 ~ 19.6 kN/m
    k_geom = DoubleWishboneParams().k_theta / 0.37 ** 2
    assert eq["k_s_series"] == pytest.approx(k_geom, rel=0.1)
    # damper 3800 N s/m at motion ratio ~0.61: ~1400 N s/m at the wheel; zeta ~ 0.2
    assert 1000 < eq["c_s"] < 1700
    assert 0.15 < eq["zeta"] < 0.25
