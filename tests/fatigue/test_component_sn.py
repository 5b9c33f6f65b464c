"""The component S-N curve (Marin/Shigley), the endurance rule shared by stress-life and
strain-life, Haibach's slope below the knee, and the [fatigue] config keys for them."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from cosim.errors import ScenarioError
from nodes.fatigue.config import FatigueConfig
from nodes.fatigue.lib.damage import cycle_reversals, strain_life_knee
from nodes.fatigue.lib.life_models import SNCurve, cyclic_strain, neuber
from nodes.fatigue.lib.material import (
    ComponentSpec,
    component_sn_curve,
    material_sn_curve,
)
from nodes.fatigue.materials import steel_817M40

MPa = 1e6
MAT = steel_817M40()
CURVE = component_sn_curve(MAT)
F_SUT = CURVE.lcf_stress  # f Sut = 0.779369 * 1277 = 995.25 MPa (test_material: f)
SE = CURVE.Se  # 0.22075 * 0.882291 * 638.5 = 124.36 MPa (test_material)


def test_component_curve_numbers():
    assert F_SUT == pytest.approx(0.779369 * 1277 * MPa, rel=1e-6)
    assert SE == pytest.approx(124.3605 * MPa, rel=1e-5)
    # B = log10(f Sut / Se) / log10(1e3 / 1e6) = -log10(995.254 / 124.3605) / 3
    #   = -log10(8.00299) / 3 = -0.903252 / 3 = -0.301084
    assert CURVE.b == pytest.approx(-0.301084, rel=1e-5)
    # a = f Sut / 10^(3B) = 995.254 * 8.00299 = 7965.0 MPa;
    # sf_c = a 2^-B = 7965.0 * exp(0.301084 * 0.693147) = 7965.0 * 1.232070 = 9813.4 MPa
    assert CURVE.meta["shigley_a_pa"] == pytest.approx(7965.0 * MPa, rel=1e-4)
    assert CURVE.sf == pytest.approx(9813.4 * MPa, rel=1e-4)
    # k = 1/0.301084 = 3.3213; Haibach k' = 2k - 1 = 5.6427
    assert CURVE.k == pytest.approx(3.3213, rel=1e-4)
    assert CURVE.k_haibach == pytest.approx(5.6427, rel=1e-4)
    assert CURVE.endurance == "haibach"


def test_curve_passes_through_its_anchor_points():
    # (10^3 cycles, f Sut) and (10^6 cycles, Se), in reversals 2e3 and 2e6
    assert CURVE.reversals(np.array([F_SUT]))[0] == pytest.approx(2e3, rel=1e-4)
    assert CURVE.reversals(np.array([SE * (1 + 1e-12)]))[0] == pytest.approx(2e6, rel=1e-4)
    np.testing.assert_allclose(CURVE.stress(np.array([2e3, 2e6])), [F_SUT, SE], rtol=1e-5)
    # Shigley's low-cycle segment: (1 cycle, Sut) = 2 reversals, straight in log-log to 10^3
    assert CURVE.reversals(np.array([1277 * MPa]))[0] == pytest.approx(2.0, rel=1e-9)
    s_mid = math.sqrt(1277 * MPa * F_SUT)  # geometric middle of the segment: 10^1.5 cycles
    assert CURVE.reversals(np.array([s_mid]))[0] == pytest.approx(2 * 10**1.5, rel=1e-6)
    # Basquin form in between: sigma_ar = sf_c (2N)^b_c at 10^4.5 cycles
    r = 2 * 10**4.5
    assert CURVE.reversals(np.array([CURVE.sf * r**CURVE.b]))[0] == pytest.approx(r)


def test_endurance_modes_below_the_knee():
    s = np.array([0.5 * SE, 0.25 * SE])
    hb = CURVE.reversals(s)
    # Haibach: 2N = 2e6 (Se / s)^(2k - 1); the slope between the two points is 2k - 1
    np.testing.assert_allclose(hb, 2e6 * np.array([2.0, 4.0]) ** (2 * CURVE.k - 1), rtol=1e-9)
    slope = math.log(hb[1] / hb[0]) / math.log(2.0)
    assert slope == pytest.approx(5.6427, rel=1e-4)
    assert np.isinf(CURVE.with_endurance("elementary").reversals(s)).all()
    none = CURVE.with_endurance("none").reversals(s)
    np.testing.assert_allclose(none, (s / CURVE.sf) ** (1 / CURVE.b))
    # above the knee the modes agree
    above = np.array([1.5 * SE, 3 * SE])
    for mode in ("elementary", "none"):
        np.testing.assert_array_equal(CURVE.with_endurance(mode).reversals(above),
                                      CURVE.reversals(above))


def test_material_option_is_the_old_curve():
    cfg = FatigueConfig.from_dict({"component": {"enabled": False}, "endurance": "none"})
    sn = cfg.material.sn
    assert (sn.sf, sn.b, sn.Se, sn.lcf_Su) == (MAT.sf, MAT.b, MAT.Se, None)
    s = np.array([300e6, 700e6])
    np.testing.assert_allclose(sn.reversals(s), (s / MAT.sf) ** (1 / MAT.b))
    # knee where the Basquin line meets Se' = 638.5 MPa: (1/3)^(1/-0.087) = 3.05e5 reversals
    assert material_sn_curve(MAT).knee_reversals == pytest.approx(3 ** (1 / 0.087), rel=1e-9)
    polished = FatigueConfig.from_dict({"component": {"surface": "polished"}}).material.sn
    assert polished.meta["factors"]["ka"] == 1.0


# ----------------------------------------------------------------- one endurance rule
def _both(s1, s2, mat, ms, mode):
    return (cycle_reversals(np.array([s1]), np.array([s2]), mat, "stress_life", ms, mode)[0],
            cycle_reversals(np.array([s1]), np.array([s2]), mat, "strain_life", ms, mode)[0])


COMP = replace(MAT, sn=CURVE)


@pytest.mark.parametrize("ms", ["goodman", "gerber", "morrow", "swt"])
def test_mean_stress_lifts_a_cycle_below_se_above_it_in_both_methods(ms):
    # sa = 0.95 Se = 118.1 MPa is below Se; with sm = +400 MPa the corrected amplitude is
    # above it: Goodman 0.95/(1 - 400/1277) = 1.38 Se, Gerber 0.95/(1 - 0.0981) = 1.053 Se,
    # Morrow 0.95/(1 - 400/1915.5) = 1.20 Se, SWT sqrt(518.1 * 118.1) = 247 MPa = 1.99 Se
    sa, sm = 0.95 * SE, 400 * MPa
    sl, el = _both(sm + sa, sm - sa, COMP, ms, "elementary")
    assert np.isfinite(sl) and np.isfinite(el)
    # and the old strain-life rule (uncorrected elastic amplitude) would have said no damage
    assert sa < SE


@pytest.mark.parametrize("ms", ["goodman", "morrow", "swt"])
def test_mean_stress_drops_a_cycle_above_se_below_it_in_both_methods(ms):
    # sa = 1.05 Se with sm = -400 MPa: Goodman 1.05/(1 + 400/1277) = 0.80 Se, Morrow
    # 1.05/(1 + 400/1915.5) = 0.87 Se, SWT sigma_max < 0 (no damage). (Gerber does not correct
    # compressive means, so it has no such case.)
    sa, sm = 1.05 * SE, -400 * MPa
    sl, el = _both(sm + sa, sm - sa, COMP, ms, "elementary")
    assert np.isinf(sl) and np.isinf(el)
    # with no endurance limit both do damage (SWT's sigma_max < 0 excepted)
    sl, el = _both(sm + sa, sm - sa, COMP, ms, "none")
    assert (np.isinf(sl) and np.isinf(el)) if ms == "swt" else (np.isfinite(sl)
                                                                and np.isfinite(el))


def test_no_mean_correction_uses_the_plain_amplitude_in_both():
    # with mean_stress = "none" the mean does not matter to the endurance test
    for s1, s2, damaged in ((0.99 * SE + 300e6, -0.99 * SE + 300e6, False),
                            (1.01 * SE + 300e6, -1.01 * SE + 300e6, True)):
        sl, el = _both(s1, s2, COMP, "none", "elementary")
        assert np.isfinite(sl) == np.isfinite(el) == damaged


def test_haibach_in_strain_life():
    # below Se: 2N = 2N_D (Se/sar)^(2k-1), 2N_D the strain-life life at sar = Se, k = -1/b
    sa = 0.5 * SE
    rev = cycle_reversals(np.array([sa]), np.array([-sa]), COMP, "strain_life", "none",
                          "haibach")[0]
    knee = strain_life_knee(SE, COMP, "none")
    k = 1 / 0.087
    # sar is the local (Neuber) amplitude, 1e-7 below the elastic one at 62 MPa
    sar = neuber(np.array([sa]), COMP)[0]
    assert sar == pytest.approx(sa, rel=1e-6)
    assert rev == pytest.approx(knee * (SE / sar) ** (2 * k - 1), rel=1e-9)
    # continuous at the knee: elastic amplitudes whose local (Neuber) amplitude is Se -+ 1e-9
    local = SE * np.array([1 - 1e-9, 1 + 1e-9])
    se = np.sqrt(COMP.E * local * cyclic_strain(local, COMP))  # Neuber: sigma eps = se^2/E
    just = cycle_reversals(se, -se, COMP, "strain_life", "none", "haibach")
    np.testing.assert_allclose(just, knee, rtol=1e-6)


def test_default_endurance_comes_from_the_curve():
    sa = 0.5 * SE
    r = cycle_reversals(np.array([sa]), np.array([-sa]), COMP, "stress_life", "none")[0]
    assert r == pytest.approx(2e6 * 2.0 ** CURVE.k_haibach, rel=1e-9)
    # a mode given as the argument overrides the curve's
    assert np.isinf(cycle_reversals(np.array([sa]), np.array([-sa]), COMP, "stress_life",
                                    "none", "elementary")[0])
    assert cycle_reversals(np.array([sa]), np.array([-sa]), COMP, "stress_life", "none",
                           "none")[0] == pytest.approx((sa / CURVE.sf) ** (1 / CURVE.b))


def test_sn_curve_checks_its_inputs():
    with pytest.raises(ValueError):
        SNCurve(sf=1e9, b=0.1, Se=1e8, knee_reversals=2e6)
    with pytest.raises(ValueError):
        SNCurve(sf=1e9, b=-0.1, Se=2e9, knee_reversals=2e6)
    with pytest.raises(ValueError):
        SNCurve(sf=1e9, b=-0.1, Se=1e8, knee_reversals=2e6, endurance="sometimes")
    with pytest.raises(ValueError):
        component_sn_curve(MAT, ComponentSpec(surface="polished", kf=2.0))  # Se > f Sut


# ----------------------------------------------------------------- config
def test_config_defaults_and_summary():
    cfg = FatigueConfig.from_dict({})
    assert cfg.endurance == "haibach"
    assert cfg.component == ComponentSpec()
    d = cfg.as_dict()
    json.dumps(d)
    sn = d["fatigue_properties"]["sn_curve"]
    assert sn["factors"]["ka"] == pytest.approx(0.22075, rel=1e-4)
    assert sn["Se_pa"] == pytest.approx(SE, rel=1e-5)
    assert sn["sf_pa"] == pytest.approx(CURVE.sf) and sn["b"] == pytest.approx(CURVE.b)
    assert sn["surface"] == "forged" and sn["endurance"] == "haibach"
    assert d["fatigue_properties"]["material"]["K"] == pytest.approx(2107.05e6)
    assert d["component"]["surface"] == "forged"


def test_config_component_keys():
    cfg = FatigueConfig.from_dict({"component": {"surface": "machined", "reliability": 0.99,
                                                 "equivalent_diameter_m": 0.032},
                                   "material": {"cyclic": "table_6_2"}})
    m = cfg.material
    assert (m.K, m.n) == (1166e6, 0.0246)
    assert m.sn.meta["factors"]["ke"] == pytest.approx(0.814, abs=5e-4)
    assert m.sn.meta["factors"]["kb"] == pytest.approx((32 / 7.62) ** -0.107)
    assert FatigueConfig.from_dict({"endurance_limit": True}).endurance == "elementary"
    assert FatigueConfig.from_dict({"endurance_limit": False}).endurance == "none"
    assert FatigueConfig.from_dict({"endurance_limit": True,
                                    "endurance": "elementary"}).endurance == "elementary"


@pytest.mark.parametrize("d,key", [
    ({"component": {"surface": "anodised"}}, "fatigue.component.surface"),
    ({"component": {"reliability": 0.3}}, "fatigue.component.reliability"),
    ({"component": {"reliability": "high"}}, "fatigue.component.reliability"),
    ({"component": {"loading": "torsion"}}, "fatigue.component.loading"),
    ({"component": {"section_h_m": -0.01}}, "fatigue.component.section_h_m"),
    ({"component": {"section_h_m": 0.001, "section_b_m": 0.001}},
     "fatigue.component.section_h_m"),
    ({"component": {"equivalent_diameter_m": 1.0}}, "fatigue.component.equivalent_diameter_m"),
    ({"component": {"kf": 0}}, "fatigue.component.kf"),
    ({"component": {"knee_cycles": 100}}, "fatigue.component.knee_cycles"),
    ({"component": {"temperature_c": 900}}, "fatigue.component.temperature_c"),
    ({"component": {"enabled": "yes"}}, "fatigue.component.enabled"),
    ({"component": {"shot_peened": True}}, "fatigue.component.shot_peened"),
    ({"component": "forged"}, "fatigue.component"),
    ({"component": {"surface": "polished", "kf": 2.0}}, "fatigue.component"),
    ({"endurance": "sometimes"}, "fatigue.endurance"),
    ({"endurance_limit": "yes"}, "fatigue.endurance_limit"),
    ({"endurance_limit": True, "endurance": "haibach"}, "fatigue.endurance_limit"),
    ({"material": {"cyclic": "haiba"}}, "fatigue.material.cyclic"),
    ({"material": {"b": 0.1}}, "fatigue.material.b"),
])
def test_config_errors_name_the_key(d, key):
    with pytest.raises(ScenarioError) as e:
        FatigueConfig.from_dict(d)
    assert e.value.key == key


def test_summary_json_reports_the_curve(tmp_path):
    # one-node imported table (no FE): the summary's config carries the factors and the curve
    from nodes.fatigue.worker import analyse
    (tmp_path / "bj_z.csv").write_text("SX,SY,SZ,SXY,SYZ,SXZ\n2.0e4,0,0,0,0,0\n")
    cfg = FatigueConfig.from_dict({"influence": str(tmp_path), "nodes": "all",
                                   "mapping": {"plant/arm/ball_joint_z": "bj_z.csv"}})
    t = np.arange(400) * 0.002
    fz = 4000.0 + 4000.0 * np.sin(2 * np.pi * 5 * t)  # 80 +- 80 MPa at the node
    r = analyse(t, {"plant/arm/ball_joint_z": fz}, cfg, 10.0)
    s = json.loads(json.dumps(r.summary()))
    sn = s["config"]["fatigue_properties"]["sn_curve"]
    assert set(sn["factors"]) >= {"ka", "kb", "kc", "kd", "ke", "kf", "Se_pa"}
    assert sn["Se_pa"] == pytest.approx(SE, rel=1e-5)
    # 4 cycles of 80 MPa at +80 MPa mean (Goodman: 80/(1 - 80/1277) = 85.35 MPa < Se):
    # Haibach: N = 1e6 (124.09/85.35)^(2k-1) per cycle
    sar = 80e6 / (1 - 80e6 / 1277e6)
    n_f = 1e6 * (SE / sar) ** (2 * CURVE.k - 1)
    assert r.max_damage == pytest.approx(r.n_cycles[0] / n_f, rel=1e-3)
