"""Miner damage against closed forms; life models against their defining equations."""

from __future__ import annotations

import numpy as np
import pytest

from nodes.fatigue.lib.counting import StreamingRainflow, count_series
from nodes.fatigue.lib.damage import cycle_reversals
from nodes.fatigue.lib.life_models import cyclic_strain, neuber
from nodes.fatigue.lib.material import compatibility, uniform_material_law, with_overrides
from nodes.fatigue.lib.mean_stress import equivalent_amplitude
from nodes.fatigue.materials import steel_817M40

from .oracle_miner import miner_per_node

MAT = steel_817M40()


def test_817m40_table_6_2_and_uml():
    assert (MAT.E, MAT.nu, MAT.rho) == (200e9, 0.3, 7800.0)
    assert (MAT.Sy, MAT.Su) == (1166e6, 1277e6)
    # Bäumel-Seeger UML by hand: psi = 1.375 - 125*1277/200000 = 0.576875
    assert MAT.sf == pytest.approx(1915.5e6)
    assert MAT.ef == pytest.approx(0.59 * 0.576875)
    assert (MAT.b, MAT.c) == (-0.087, -0.58)
    # the cyclic curve is the UML's own since issue #12: K' = 1.65 * 1277 = 2107.05 MPa, n' = 0.15
    assert (MAT.K, MAT.n) == (pytest.approx(2107.05e6), 0.15)
    assert uniform_material_law(500e6, 200e9)["ef"] == pytest.approx(0.59)  # psi = 1
    comp = compatibility(MAT)
    assert comp["n_implied"] == pytest.approx(0.15)
    # Table 6.2's pair is still there on request
    t62 = steel_817M40("table_6_2")
    assert (t62.K, t62.n) == (1166e6, 0.0246)


def test_overrides():
    m = with_overrides(MAT, {"sf'": 2000e6, "b": -0.1})
    assert (m.sf, m.b, m.c) == (2000e6, -0.1, MAT.c)
    with pytest.raises(KeyError):
        with_overrides(MAT, {"bogus": 1.0})


def _sine(amplitude, mean, n_cycles, per_cycle=40):
    t = np.arange(n_cycles * per_cycle) / per_cycle
    return mean + amplitude * np.sin(2 * np.pi * t)


@pytest.mark.parametrize("ms", ["none", "goodman", "gerber", "morrow", "swt"])
def test_miner_constant_amplitude_closed_form(ms):
    sa, sm, n = 300e6, 150e6, 25
    x = _sine(sa, sm, n)
    c = count_series(x, "repeated")
    D = miner_per_node(c, 1, MAT, "stress_life", ms)[0]
    # closed forms of the equivalent amplitude, then Basquin Nf = 0.5 (σar/σ'f)^(1/b)
    sar = {"none": sa, "goodman": sa / (1 - sm / MAT.Su),
           "gerber": sa / (1 - (sm / MAT.Su) ** 2), "morrow": sa / (1 - sm / MAT.sf),
           "swt": np.sqrt((sm + sa) * sa)}[ms]
    Nf = 0.5 * (sar / MAT.sf) ** (1 / MAT.b)
    assert D == pytest.approx(n / Nf, rel=1e-9)


def test_miner_half_cycle_residue_and_endurance_limit():
    sa, n = 400e6, 10
    x = _sine(sa, 0.0, n)
    c = count_series(x, "half_cycles")
    Nf = 0.5 * (sa / MAT.sf) ** (1 / MAT.b)
    # a sine from 0 up: n-1 full cycles closed + 3 half cycles (0->+sa, ..., -sa->~0):
    D = miner_per_node(c, 1, MAT, "stress_life", "none")[0]
    assert D == pytest.approx((n - 0.5) / Nf + 0.5 * _half_damage(x, c), rel=1e-6)
    assert miner_per_node(c, 1, MAT, "stress_life", "none", endurance_limit="elementary")[0] == 0.0


def _half_damage(x, c):
    # damage of the half-cycle that is not at full amplitude (sine end back to ~0)
    sel = (c.count == 0.5) & (c.range < 1.9 * 400e6)
    sar = c.range[sel] / 2
    return float(np.sum(1 / (0.5 * (sar / MAT.sf) ** (1 / MAT.b))))


def test_miner_per_node_streaming_equals_closed_form_per_node():
    amps = np.array([100e6, 200e6, 350e6])
    n = 12
    x = np.stack([_sine(a, 0.0, n) for a in amps], axis=1)
    rf = StreamingRainflow(3)
    cyc = rf.feed(x)
    from nodes.fatigue.lib.counting import Cycles
    c = Cycles.concat([cyc, rf.residue_cycles("repeated")])
    D = miner_per_node(c, 3, MAT, "stress_life", "none")
    Nf = 0.5 * (amps / MAT.sf) ** (1 / MAT.b)
    np.testing.assert_allclose(D, n / Nf, rtol=1e-9)


def test_mean_stress_signs():
    sa = np.array([100e6, 100e6])
    sm = np.array([-200e6, 200e6])
    g = equivalent_amplitude(sa, sm, "goodman", MAT.Su, MAT.sf)
    assert g[0] < 100e6 < g[1]
    ge = equivalent_amplitude(sa, sm, "gerber", MAT.Su, MAT.sf)
    assert ge[0] == 100e6 and ge[1] > 100e6
    swt = equivalent_amplitude(np.array([100e6]), np.array([-150e6]), "swt", MAT.Su, MAT.sf)
    assert swt[0] == 0.0  # σmax < 0: no damage
    assert np.isinf(equivalent_amplitude(sa, np.array([2e9, 2e9]), "goodman", MAT.Su, MAT.sf)).all()


def test_neuber_and_strain_life_closed_form():
    # choose a local amplitude, build the elastic amplitude it corresponds to by Neuber in
    # closed form, and check the solver recovers it and the CMB life satisfies CMB.
    sa_local = np.array([300e6, 900e6, 1050e6])
    ea = sa_local / MAT.E + (sa_local / MAT.K) ** (1 / MAT.n)
    se = np.sqrt(MAT.E * sa_local * ea)
    np.testing.assert_allclose(neuber(se, MAT), sa_local, rtol=1e-9)
    np.testing.assert_allclose(cyclic_strain(sa_local, MAT), ea)
    rev = cycle_reversals(se, -se, MAT, "strain_life", "none")
    cmb = MAT.sf / MAT.E * rev**MAT.b + MAT.ef * rev**MAT.c
    np.testing.assert_allclose(cmb, ea, rtol=1e-9)
    # in the elastic range strain-life with no mean = Basquin
    r_el = cycle_reversals(np.array([200e6]), np.array([-200e6]), MAT, "strain_life", "none")
    r_sn = cycle_reversals(np.array([200e6]), np.array([-200e6]), MAT, "stress_life", "none")
    assert r_el[0] == pytest.approx(r_sn[0], rel=2e-3)


def test_strain_life_swt_and_morrow_equations():
    s1, s2 = np.array([700e6]), np.array([-100e6])
    sa_local = neuber(np.array([400e6]), MAT)
    ea = cyclic_strain(sa_local, MAT)
    peak = neuber(np.array([700e6]), MAT)
    sm = peak - sa_local
    rev = cycle_reversals(s1, s2, MAT, "strain_life", "morrow")
    np.testing.assert_allclose((MAT.sf - sm) / MAT.E * rev**MAT.b + MAT.ef * rev**MAT.c,
                               ea, rtol=1e-8)
    rev = cycle_reversals(s1, s2, MAT, "strain_life", "swt")
    lhs = (sm + sa_local) * ea
    rhs = MAT.sf**2 / MAT.E * rev ** (2 * MAT.b) + MAT.sf * MAT.ef * rev ** (MAT.b + MAT.c)
    np.testing.assert_allclose(rhs, lhs, rtol=1e-8)
