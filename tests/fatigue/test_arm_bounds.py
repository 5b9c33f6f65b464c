"""The mode-stress closed form (nodes/fatigue/lib/arm_bounds.py) against the part FE's bar
(P2 tetrahedra, nodes/fatigue/lib/solid.py), and what it says about issue #12's bars."""

from __future__ import annotations

import math

import numpy as np
import pytest
from skfem import MeshTet

from nodes.fatigue.lib import arm_bounds as ab
from nodes.fatigue.lib.solid import PartFE, TetMesh

E, NU, RHO = 200e9, 0.3, 7800.0


@pytest.fixture(scope="module")
def bar():
    """A slender steel bar (L/h = 20), free-free, 16 x 2 x 2 cubes of P2 tetrahedra: its first
    flexible mode is bending about the weak axis."""
    L, b, h = 0.4, 0.04, 0.02
    m = MeshTet.init_tensor(np.linspace(0, L, 17), np.linspace(-b / 2, b / 2, 3),
                            np.linspace(-h / 2, h / 2, 3))
    fe = PartFE(TetMesh(m.p.T.copy(), m.t.T.copy(), np.arange(m.p.shape[1])), E, NU, RHO)
    return L, b, h, fe, float(fe.modes(1)[0][0])


def test_stress_from_frequency_matches_beam_theory(bar):
    """σ from (mass, length, FE frequency, κ) equals M c / I of the same bar."""
    L, b, h, fe, f1 = bar
    m = RHO * L * b * h
    M = 1000.0
    sigma_beam = M * (h / 2) / (b * h**3 / 12)
    kappa = 1.0 / math.sqrt(3.0)  # solid rectangle: r = h / sqrt(12), c = h / 2
    s = ab.nominal_bending_stress(M, m, L, f1, E, RHO, kappa=kappa)
    assert s == pytest.approx(sigma_beam, rel=0.02)
    # the floor (κ = 1, all material at the extreme fibres) is lower by exactly sqrt(3)
    floor = ab.nominal_bending_stress(M, m, L, f1, E, RHO)
    assert floor == pytest.approx(s / math.sqrt(3.0), rel=1e-12)


def test_softer_arm_is_more_stressed():
    """Issue #12's bars together: 5 kg ± 10 %, 0.3 m legs, the torsion spring's 1.58 kN m.
    At Table 6.1's 362 Hz + 15 % (416 Hz), even the ideal section (κ = 1) at the heaviest
    allowed mass is nominally above the 250 MPa hot-spot bar."""
    s = ab.nominal_bending_stress(1583.0, 5.5, 0.32, 362.3 * 1.15, E, RHO)
    assert s > 250e6


def test_rejects_nonphysical_input():
    with pytest.raises(ValueError):
        ab.nominal_bending_stress(1.0, 5.0, 0.3, 300.0, E, RHO, kappa=1.5)
    with pytest.raises(ValueError):
        ab.nominal_bending_stress(1.0, 0.0, 0.3, 300.0, E, RHO)
