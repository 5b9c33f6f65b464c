"""#26 item 4 / #30 item 4: S-N curves as data (point table, nCode segments), the FKM
guideline's factors and mean-stress rule, the material database and the material's name."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from cosim.errors import ScenarioError
from nodes.fatigue.config import FatigueConfig
from nodes.fatigue.lib.counting import Cycles
from nodes.fatigue.lib.fkm import FKMSpec, fkm_factors, fkm_sn_curve, roughness_factor
from nodes.fatigue.lib.material import (
    component_sn_curve,
    with_overrides,
)
from nodes.fatigue.lib.mean_stress import equivalent_amplitude
from nodes.fatigue.lib.sn_data import ncode_curve, points_curve
from nodes.fatigue.materials import database_material, steel_817M40

from .oracle_miner import miner_per_node


def random_cycles(n: int = 4000, seed: int = 2) -> Cycles:
    rng = np.random.default_rng(seed)
    amp = 10.0 ** rng.uniform(7.3, 8.9, n)  # 20-800 MPa amplitudes
    mean = rng.uniform(-150e6, 250e6, n)
    return Cycles(series=rng.integers(0, 7, n), s1=mean + amp, s2=mean - amp,
                  count=np.where(rng.random(n) < 0.2, 0.5, 1.0))


@pytest.mark.parametrize("endurance, b2", [("haibach", "haibach"), ("elementary", 0.0),
                                           ("none", "none")])
def test_ncode_and_point_table_give_the_basquin_damage(endurance: str, b2) -> None:
    """The Shigley component curve (above its low-cycle segment), as an nCode curve
    (SRI1 = 2 σ'f 2^b, b1 = b, Nc1 = N_D, b2) and as a point table: the same damage."""
    mat = steel_817M40()
    sn = component_sn_curve(mat, endurance=endurance)
    sn = replace(sn, lcf_Su=None)  # the data curves below have no Shigley low-cycle line
    k = sn.k
    ND = sn.knee_reversals / 2
    tail = {"haibach": -1.0 / (2 * k - 1), "none": sn.b}.get(b2, b2)
    nc = ncode_curve(2 * sn.sf * 2**sn.b, sn.b, ND, tail)
    pts = points_curve([[1e3, sn.sf * 2e3**sn.b], [ND, sn.Se]], endurance=endurance)
    pts_range = points_curve([[1e3, 2 * sn.sf * 2e3**sn.b], [ND, 2 * sn.Se]], "range",
                             endurance=endurance)
    cyc = random_cycles()
    ref = miner_per_node(cyc, 7, replace(mat, sn=sn), "stress_life", "goodman", endurance)
    assert ref.min() > 0
    for curve in (nc, pts, pts_range):
        d = miner_per_node(cyc, 7, replace(mat, sn=curve), "stress_life", "goodman",
                           endurance)
        np.testing.assert_allclose(d, ref, rtol=1e-10)


def test_point_table_interpolates_log_log_between_points() -> None:
    c = points_curve([[1e3, 800e6], [1e5, 400e6], [1e6, 200e6]], endurance="elementary")
    # halfway in log S between 400 and 800 MPa: halfway in log N between 1e3 and 1e5
    rev = c.reversals(np.array([np.sqrt(400e6 * 800e6), 150e6]))
    assert rev[0] == pytest.approx(2e4, rel=1e-12)
    assert rev[1] == np.inf
    np.testing.assert_allclose(c.stress(np.array([2e3, 2e5, 2e6])), [800e6, 400e6, 200e6])


def test_fkm_factors_by_hand() -> None:
    """FKM at Rm = 1277 MPa, Rz = 200 µm (issue #26's numbers): K_R = 0.592, M = 0.347."""
    kr = 1 - 0.22 * np.log10(200) * np.log10(2 * 1277 / 400)
    assert roughness_factor(1277e6, 200.0) == pytest.approx(kr, rel=1e-12)
    assert kr == pytest.approx(0.5924, abs=1e-4)
    f = fkm_factors(1277e6, FKMSpec(), 0.975)
    assert f["M_sigma"] == pytest.approx(0.35 * 1.277 - 0.1, rel=1e-12)
    assert f["sigma_WK_pa"] == pytest.approx(0.45 * 1277e6 * kr, rel=1e-12)
    med = fkm_factors(1277e6, FKMSpec(), 0.5)["sigma_WK_pa"]
    assert med / f["sigma_WK_pa"] == pytest.approx(1 / (1 - 0.08 * 1.959964), rel=1e-5)
    c = fkm_sn_curve(1277e6, FKMSpec(), "none", 0.975)
    assert c.k == pytest.approx(5.0)
    # slope 5 through the knee: ten times the life at 10^(-1/5) of the stress
    rev = c.reversals(np.array([c.Se, c.Se * 10 ** (1 / 5)]))
    assert rev[0] / rev[1] == pytest.approx(10.0, rel=1e-9)
    # FKM's size factor: 1 up to d_eff,N; below 1 above it
    big = fkm_factors(1277e6, FKMSpec(d_eff_m=0.06), 0.975)
    num = 1 - 0.7686 * 0.3 * np.log10(60 / 7.5)
    den = 1 - 0.7686 * 0.3 * np.log10(16 / 7.5)
    assert big["K_dm"] == pytest.approx(num / den, rel=1e-12) and big["K_dm"] < 1


def test_fkm_haigh_regions() -> None:
    M = 0.3
    sa = np.full(5, 100.0)
    sm = np.array([-200.0, -100.0, 50.0, 200.0, 400.0])
    got = equivalent_amplitude(sa, sm, "fkm", 1e9, 1e9, M)
    want = [100 * (1 - M), 100 - M * 100, 100 + M * 50,
            (100 + M * 200 / 3) * (1 + M) / (1 + M / 3), 100 * (1 + M) ** 2 * 3 / (3 + M)]
    np.testing.assert_allclose(got, want, rtol=1e-12)
    # continuous at R = 0 (σm = σa) and R = 0.5 (σm = 3 σa)
    for r in (1.0, 3.0):
        lo, hi = equivalent_amplitude(np.array([1.0, 1.0]), np.array([r - 1e-9, r + 1e-9]),
                                      "fkm", 1e9, 1e9, M)
        assert lo == pytest.approx(hi, rel=1e-7)


def test_database_817m40_is_table_6_2_and_names_follow_overrides() -> None:
    m = database_material("817M40")
    assert (m.E, m.nu, m.rho, m.Su, m.Sy) == (200e9, 0.3, 7800.0, 1277e6, 1166e6)
    assert m.source["Su"] == "thesis Table 6.2"
    assert database_material("817M40", "table_6_2").n == 0.0246
    assert m.name == "817M40"
    assert with_overrides(m, {"E": 210e9, "Su": 310e6, "Sy": 275e6}).name == \
        "817M40 with E, Su, Sy overridden"
    cfg = FatigueConfig.from_dict({"material": {"Su": 310e6, "Sy": 275e6},
                                   "component": {"enabled": False}})
    assert cfg.as_dict()["fatigue_properties"]["material"]["name"] == \
        "817M40 with Su, Sy overridden"
    other = FatigueConfig.from_dict({"material": {"name": "42CrMo4+QT"}}).material
    assert other.name == "42CrMo4+QT" and other.Su == 1100e6
    assert "EN 10083-3" in other.source["Su"]


def test_config_selects_the_curve_and_names_bad_keys() -> None:
    assert FatigueConfig.from_dict({}).material.sn.name.startswith("component (Marin")
    fkm = FatigueConfig.from_dict({"component": {"method": "fkm", "fkm": {"rz_um": 100}}})
    assert fkm.material.sn.meta["factors"]["K_R_sigma"] == pytest.approx(
        roughness_factor(1277e6, 100.0))
    seg = FatigueConfig.from_dict({"sn_curve": {"type": "segments", "sri1_pa": 3e9,
                                                "b1": -0.2, "nc1": 2e6, "b2": -0.05}})
    assert seg.material.sn.meta["sn_method"] == "segments"
    for bad, key in [({"component": {"method": "bogus"}}, "fatigue.component.method"),
                     ({"component": {"fkm": {"k_slope": 1}}}, "fatigue.component.fkm.k_slope"),
                     ({"sn_curve": {"type": "points", "points": [[1e3, 1e8], [1e6, 2e8]]}},
                      "fatigue.sn_curve.points"),
                     ({"sn_curve": {"type": "segments", "sri1_pa": 1e9, "b1": 0.1,
                                    "nc1": 1e6}}, "fatigue.sn_curve.b1"),
                     ({"material": {"name": "unobtainium"}}, "fatigue.material.name")]:
        with pytest.raises(ScenarioError) as e:
            FatigueConfig.from_dict(bad)
        assert e.value.key == key, (bad, e.value)


def test_estimates_follow_an_overridden_strength() -> None:
    """σ'f = 1.5 σu (UML) and Se' = 0.5 σu (Shigley) follow an overridden σu; a constant
    given explicitly stays."""
    m = FatigueConfig.from_dict({"material": {"Su": 310e6, "Sy": 275e6}}).material
    assert m.sf == pytest.approx(1.5 * 310e6) and m.Se == pytest.approx(0.5 * 310e6)
    assert m.source["Su"] == "scenario override"
    m2 = FatigueConfig.from_dict({"material": {"Su": 310e6, "sf": 2e9}}).material
    assert m2.sf == 2e9 and m2.K == pytest.approx(1.65 * 310e6)
