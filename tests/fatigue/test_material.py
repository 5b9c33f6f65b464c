"""Material constants and each Marin factor against hand-worked values (arithmetic written out).

Source of every formula: Shigley's Mechanical Engineering Design, 9th ed. (Budynas & Nisbett
2011), Sec 6-7 to 6-9; Bäumel & Seeger (1990) for the Uniform Material Law.
"""

from __future__ import annotations

import math

import pytest

from nodes.fatigue.lib.material import (
    ComponentSpec,
    Material,
    compatibility,
    fatigue_strength_fraction,
    marin_factors,
    rectangle_equivalent_diameter,
    reliability_factor,
    size_factor,
    specimen_endurance_limit,
    surface_factor,
    temperature_factor,
    with_overrides,
)
from nodes.fatigue.materials import steel_817M40

MPa = 1e6
MAT = steel_817M40()


def test_uml_constants_and_cyclic_options():
    # UML: K' = 1.65 * 1277 = 2107.05 MPa, n' = 0.15; sf = 1.5 * 1277 = 1915.5 MPa
    assert MAT.K == pytest.approx(2107.05 * MPa) and MAT.n == 0.15
    comp = compatibility(MAT)
    # n' = b/c = 0.087/0.58 = 0.15; K' = 1915.5 / 0.3403563^0.15
    #   ln 0.3403563 = -1.077763, * 0.15 = -0.161664, exp = 0.850728 -> 2251.60 MPa
    assert comp["n_implied"] == pytest.approx(0.15)
    assert comp["K_implied"] == pytest.approx(2251.60 * MPa, rel=1e-5)
    assert comp["K_ratio"] == pytest.approx(2107.05 / 2251.60, rel=1e-5)  # 0.9358
    t62 = steel_817M40("table_6_2")
    assert (t62.K, t62.n) == (1166 * MPa, 0.0246)
    assert compatibility(t62)["K_ratio"] == pytest.approx(1166 / 2251.60, rel=1e-5)
    c = steel_817M40("compatible")
    assert c.K == pytest.approx(comp["K_implied"]) and c.n == pytest.approx(0.15)
    with pytest.raises(ValueError):
        steel_817M40("haiba")


def test_material_checks_its_inputs():
    with pytest.raises(ValueError):
        with_overrides(MAT, {"b": 0.1})  # a fatigue exponent must be negative
    with pytest.raises(ValueError):
        with_overrides(MAT, {"Su": -1.0})
    with pytest.raises(ValueError):
        Material(**{**MAT.as_dict(), "nu": 0.5})


def test_specimen_endurance_limit():
    # Shigley Eq 6-8: 0.5 * 1277 = 638.5 MPa; above 1400 MPa a flat 700 MPa
    assert MAT.Se == specimen_endurance_limit(1277 * MPa) == pytest.approx(638.5 * MPa)
    assert specimen_endurance_limit(1600 * MPa) == 700 * MPa


@pytest.mark.parametrize("surface,Su,expected", [
    # Shigley Example 6-3: machined, 520 MPa: 4.51 * 520^-0.265 = 0.860; forged 0.540
    ("machined", 520, 0.860),
    ("forged", 520, 0.540),
    # 817M40, 1277 MPa (ln 1277 = 7.152269):
    # forged:     272 * exp(-0.995 * 7.152269) = 272 / 1232.15 = 0.22075
    ("forged", 1277, 0.22075),
    # hot-rolled: 57.7 * exp(-0.718 * 7.152269) = 57.7 / 169.913 = 0.33959
    ("hot_rolled", 1277, 0.33959),
    # machined:   4.51 * exp(-0.265 * 7.152269) = 4.51 / 6.65476 = 0.67771
    ("machined", 1277, 0.67771),
    # ground:     1.58 * exp(-0.085 * 7.152269) = 1.58 / 1.83671 = 0.86024
    ("ground", 1277, 0.86024),
    ("polished", 1277, 1.0),
    # ground at 100 MPa would be 1.58 * 100^-0.085 = 1.067: capped at 1
    ("ground", 100, 1.0),
])
def test_surface_factor(surface, Su, expected):
    assert surface_factor(Su * MPa, surface) == pytest.approx(expected, abs=6e-4)


def test_size_factor():
    # the arm's default section, 42 mm deep x 22 mm (both ribs): Eq 6-25
    # d_e = 0.808 * sqrt(42 * 22) = 0.808 * 30.3974 = 24.5611 mm
    d_e = rectangle_equivalent_diameter(0.042, 0.022)
    assert d_e == pytest.approx(24.5611e-3, rel=1e-5)
    # Eq 6-20: kb = (24.5611 / 7.62)^-0.107 = exp(-0.107 * ln 3.223242)
    #            = exp(-0.107 * 1.170388) = exp(-0.125232) = 0.882291
    #   (Shigley's rounded form 1.24 * 24.5611^-0.107 = 0.88039 is 0.2 % lower)
    assert size_factor(d_e) == pytest.approx(0.882291, rel=1e-5)
    assert size_factor(d_e) == pytest.approx(1.24 * 24.5611**-0.107, rel=3e-3)
    # 32 mm (Shigley Example 6-4's shaft): (32 / 7.62)^-0.107 = 0.858; the 7.62 mm specimen: 1
    assert size_factor(0.032) == pytest.approx(0.858, abs=5e-4)
    assert size_factor(0.00762) == pytest.approx(1.0)
    # large range: 1.51 * 100^-0.157 = 1.51 * 0.485289 = 0.73279
    assert size_factor(0.100) == pytest.approx(0.73279, rel=1e-4)
    assert size_factor(0.100, "axial") == 1.0  # Eq 6-21: no size effect in axial loading
    with pytest.raises(ValueError):
        size_factor(0.001)
    with pytest.raises(ValueError):
        size_factor(0.3)


def test_temperature_and_reliability_factors():
    assert temperature_factor(20.0) == 1.0
    # 250 °C = 482 °F: 0.975 + 0.432e-3*482 - 0.115e-5*482^2 + 0.104e-8*482^3 - 0.595e-12*482^4
    #   = 0.975 + 0.208224 - 0.267173 + 0.116459 - 0.032115 = 1.000396 (Table 6-4: 1.000)
    assert temperature_factor(250.0) == pytest.approx(1.000396, abs=2e-6)
    # Eq 6-29 / Table 6-5: ke = 1 - 0.08 z_a
    assert reliability_factor(0.5) == 1.0
    assert reliability_factor(0.90) == pytest.approx(1 - 0.08 * 1.281552, abs=1e-6)  # 0.897
    assert reliability_factor(0.95) == pytest.approx(0.868, abs=5e-4)  # z 1.645
    assert reliability_factor(0.99) == pytest.approx(0.814, abs=5e-4)  # z 2.326
    assert reliability_factor(0.999) == pytest.approx(0.753, abs=5e-4)  # z 3.090
    with pytest.raises(ValueError):
        reliability_factor(0.3)


def test_fatigue_strength_fraction():
    # Shigley Eq 6-10..6-12 for 1277 MPa: sigma'F = 1277 + 345 = 1622 MPa,
    # b' = -log10(1622 / 638.5) / log10(2e6) = -0.404887 / 6.301030 = -0.0642573,
    # f = 1622/1277 * 2000^b' = 1.270165 * 10^(3.301030 * -0.0642573) = 1.270165 * 0.613600
    assert fatigue_strength_fraction(1277 * MPa, 638.5 * MPa) == pytest.approx(0.77937,
                                                                               rel=1e-4)
    # Shigley's worked case 105 kpsi = 723.95 MPa, Se' = 52.5 kpsi: f = 0.837
    assert fatigue_strength_fraction(723.95 * MPa, 361.97 * MPa) == pytest.approx(0.837,
                                                                                  abs=1e-3)
    assert fatigue_strength_fraction(400 * MPa, 200 * MPa) == 0.9  # Sut < 70 kpsi


def test_marin_chain_default_arm():
    m = marin_factors(MAT, ComponentSpec())
    # ka 0.22075 * kb 0.882291 * kc 1 * kd 1 * ke 1 (median) * kf 1 = 0.194767
    assert (m.kc, m.kd, m.ke, m.kf) == (1.0, 1.0, 1.0, 1.0)
    assert m.product == pytest.approx(0.22075 * 0.882291, rel=1e-4)
    # Se = 0.194767 * 638.5 MPa = 124.36 MPa
    assert m.Se == pytest.approx(124.36 * MPa, rel=1e-4)
    axial99 = marin_factors(MAT, ComponentSpec(loading="axial", reliability=0.99))
    # axial: kb = 1, kc = 0.85; R 99 %: ke = 0.81390 -> Se = 0.22074*0.85*0.8139*638.5 = 97.51
    assert (axial99.kb, axial99.kc) == (1.0, 0.85)
    assert axial99.Se == pytest.approx(0.22074 * 0.85 * 0.81390 * 638.5 * MPa, rel=2e-4)
    direct = marin_factors(MAT, ComponentSpec(d_e_m=0.032))
    assert direct.kb == pytest.approx((32 / 7.62) ** -0.107)


@pytest.mark.parametrize("kw", [
    {"surface": "anodised"}, {"loading": "torsion"}, {"reliability": 0.2},
    {"section_h_m": 0.001, "section_b_m": 0.001}, {"kf": 0.0}, {"knee_cycles": 10.0},
    {"temperature_c": 900.0},
])
def test_component_spec_checks_its_inputs(kw):
    with pytest.raises(ValueError):
        ComponentSpec(**kw)


def test_de_formula_is_the_95_percent_area_equivalence():
    # 0.05 h b = 0.0766 d_e^2  ->  d_e = sqrt(0.05/0.0766) sqrt(h b) = 0.8079 sqrt(h b)
    assert math.sqrt(0.05 / 0.0766) == pytest.approx(0.808, abs=1e-3)
