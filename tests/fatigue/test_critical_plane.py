"""#44 item 1: Findley critical planes (nodes/fatigue/lib/critical_plane.py), checked against
closed forms.

Findley on the plane of normal angle θ to the load axis, k its normal-stress factor
(Socie & Marquis, Multiaxial Fatigue, 2000, Ch. 4), U = (k + sqrt(1 + k²)) / 2:

* fully reversed uniaxial σa:   f = σa U                at θ = ½ atan(1 / k);
* fully reversed torsion τa:    f = τa sqrt(1 + k²)     at θ = ½ atan(k);
* tension σx = 2τa sin ωt with torsion τxy = τa sin(ωt + δ) (thin tube surface):
  in phase (δ = 0, proportional, principal stresses τa (1 ± √2)):
      f = τa (k + √2 sqrt(1 + k²));
  90° out of phase (δ = 90°): the shear amplitude is τa on every plane (a circular shear
  path: τ(θ) = -τa (sin2θ sin ωt + cos2θ cos ωt)) and σn,max = 2 τa |cos θ|, so
      f = τa (1 + 2k)  at θ = 0 (the plane normal to the tube axis);
  f_in / f_out = (k + √2 sqrt(1 + k²)) / (1 + 2k) (1.17 at k = 0.183): Findley, a stress
  criterion, finds the out-of-phase case at equal amplitudes milder, the known limit of
  stress-based critical-plane models without non-proportional hardening (Socie & Marquis
  2000, Ch. 4 and 8). Derived here from the plane transformation (not a table value).

The life of a cycle is that of the uniaxial amplitude σ_eq = f / U on the S-N curve, so the
tests compare damage with n / N(σ_eq) of an independent Basquin line.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from nodes.fatigue.lib import critical_plane as cp
from nodes.fatigue.lib.counting import count_series

SF, B = 1.2e9, -0.1  # a Basquin line σa = σ'f (2N)^b for the tests [Pa]
PERIODS = 20
T = np.linspace(0.0, PERIODS * 2 * np.pi, PERIODS * 72 + 1)


def reversals(s: np.ndarray) -> np.ndarray:
    s = np.asarray(s, dtype=float)
    with np.errstate(divide="ignore", over="ignore"):
        return np.where(s > 0, (np.maximum(s, 1e-300) / SF) ** (1.0 / B), np.inf)


def damage_of(sigma_eq: float) -> float:
    """PERIODS cycles of amplitude sigma_eq on the Basquin line."""
    return PERIODS / (0.5 * (sigma_eq / SF) ** (1.0 / B))


def history(sx=0.0, txy=0.0) -> np.ndarray:
    s = np.zeros((T.size, 6))
    s[:, 0], s[:, 3] = sx, txy
    return s


K = cp.FINDLEY_K
U = cp.uniaxial_factor(K)


def test_k_from_the_fatigue_limit_ratio() -> None:
    # k = (2 - r) / (2 sqrt(r - 1)), r = 1 / 0.59; check by maximising f over planes
    assert K == pytest.approx((2 - 1 / 0.59) / (2 * math.sqrt(1 / 0.59 - 1)))
    th = np.linspace(0, np.pi, 200001)
    f_bend = np.max(0.5 * np.sin(2 * th) + K * np.cos(th) ** 2)  # σa = 1
    f_tors = np.max(np.abs(np.cos(2 * th)) + K * np.abs(np.sin(2 * th)))  # τa = 1
    assert f_bend == pytest.approx(U, rel=1e-9)
    assert 0.59 * f_tors == pytest.approx(f_bend, rel=1e-9)  # equal f at t-1 = 0.59 f-1
    with pytest.raises(ValueError, match="t-1/f-1"):
        cp.findley_k(0.4)


@pytest.mark.parametrize("surface", [True, False])
def test_uniaxial_is_the_sn_life_of_its_amplitude(surface: bool, monkeypatch) -> None:
    monkeypatch.setattr(cp, "TRACTION_MAX", 0.05 if surface else -1.0)
    sa = 200e6
    r = cp.findley_node(history(sx=sa * np.sin(T)), reversals, K)
    assert r.surface is surface
    assert r.f_max == pytest.approx(U * sa, rel=2e-4)  # the 1° refined (10° hemisphere) step
    assert r.damage == pytest.approx(damage_of(sa), rel=3e-3)
    theta = math.degrees(math.acos(abs(r.normal[0])))
    assert theta == pytest.approx(math.degrees(0.5 * math.atan(1 / K)), abs=5.1)
    assert r.rotation_factor < 0.05  # proportional


def test_torsion_closed_form_and_plane() -> None:
    ta = 150e6
    r = cp.findley_node(history(txy=ta * np.sin(T)), reversals, K)
    assert r.surface
    assert r.f_max == pytest.approx(ta * math.sqrt(1 + K * K), rel=1e-3)
    assert r.damage == pytest.approx(damage_of(ta * math.sqrt(1 + K * K) / U), rel=1e-2)
    # σ_eq = τa r: torsion at t-1 is as damaging as bending at f-1
    assert math.sqrt(1 + K * K) / U == pytest.approx(1 / 0.59, rel=1e-9)
    phi = math.degrees(math.atan2(abs(r.normal[1]), abs(r.normal[0])))
    assert min(phi, 90 - phi) == pytest.approx(math.degrees(0.5 * math.atan(K)), abs=1.0)


def test_out_of_phase_tension_torsion() -> None:
    ta = 100e6
    inph = cp.findley_node(history(sx=2 * ta * np.sin(T), txy=ta * np.sin(T)), reversals, K)
    oop = cp.findley_node(history(sx=2 * ta * np.sin(T), txy=ta * np.cos(T)), reversals, K)
    f_in = ta * (K + math.sqrt(2) * math.sqrt(1 + K * K))
    f_out = ta * (1 + 2 * K)
    assert inph.f_max == pytest.approx(f_in, rel=1e-3)
    assert oop.f_max == pytest.approx(f_out, rel=1e-6)
    assert inph.f_max / oop.f_max == pytest.approx(f_in / f_out, rel=1e-3)
    assert oop.damage == pytest.approx(damage_of(f_out / U), rel=1e-6)
    assert abs(oop.normal[0]) == pytest.approx(1.0, abs=1e-9)  # normal to the tube axis
    # σn,max of the critical plane is mid-way between the shear turning points: the
    # payload carries it (σn at the shear peaks alone would give f = τa)
    assert oop.rotation_factor == pytest.approx(1.0, abs=1e-3)  # circular shear path
    assert inph.rotation_factor < 0.05


def test_hemisphere_search_agrees_on_the_out_of_phase_case(monkeypatch) -> None:
    s = history(sx=200e6 * np.sin(T), txy=100e6 * np.cos(T))
    surf = cp.findley_node(s, reversals, K)
    monkeypatch.setattr(cp, "TRACTION_MAX", -1.0)
    hemi = cp.findley_node(s, reversals, K)
    assert not hemi.surface and hemi.n_paths > 1000
    assert hemi.damage == pytest.approx(surf.damage, rel=1e-6)


@pytest.mark.parametrize("residue", ["repeated", "half_cycles"])
def test_shear_counter_gives_the_project_rainflow(residue: str) -> None:
    rng = np.random.default_rng(4)
    x = np.cumsum(rng.normal(size=(400, 5)), axis=0)
    p = rng.normal(size=x.shape)
    cyc = cp.count_shear(x, p, residue)
    for j in range(x.shape[1]):
        ref = count_series(x[:, j], residue)
        mine = np.sort(np.repeat(2 * cyc.tau_a[cyc.series == j],
                                 (2 * cyc.count[cyc.series == j]).astype(int)))
        want = np.sort(np.repeat(ref.range, (2 * ref.count).astype(int)))
        np.testing.assert_allclose(mine, want, rtol=0, atol=1e-12)
        sel = cyc.series == j
        assert np.all(cyc.sn_max[sel] <= p[:, j].max())  # a payload is some sample's p


def test_surface_normal_is_the_traction_free_direction() -> None:
    rng = np.random.default_rng(1)
    n_true = np.array([1.0, 2.0, 2.0]) / 3.0
    e1, e2 = cp._basis(n_true)
    s = np.zeros((50, 6))
    for i in range(50):  # plane stress in the (e1, e2) plane
        a, b, c = rng.normal(size=3)
        M = a * np.outer(e1, e1) + b * np.outer(e2, e2) + c * (np.outer(e1, e2)
                                                                + np.outer(e2, e1))
        s[i] = [M[0, 0], M[1, 1], M[2, 2], M[0, 1], M[1, 2], M[2, 0]]
    n, ratio = cp.surface_normal(s)
    assert ratio < 1e-7 and abs(n @ n_true) == pytest.approx(1.0, abs=1e-9)


# ------------------------------------------------------------------- CLI on a run folder
@pytest.fixture()
def run_dir(tmp_path: Path) -> Path:
    """A 0.4 s history: wheel loads with a torsion-bar moment 90° out of phase."""
    d = tmp_path / "run"
    d.mkdir()
    t = np.arange(0.0, 0.4, 1e-3)
    cols = {"plant/arm/ball_joint_z": 5400 + 2500 * np.sin(50 * t),
            "plant/arm/ball_joint_x": 1500 * np.cos(50 * t),
            "plant/arm/torsion_bar_mx": -1580 - 600 * np.cos(50 * t),
            "plant/arm/bush_front_z": -2700 - 1200 * np.sin(50 * t),
            "plant/arm/bush_rear_z": -2700 - 1300 * np.sin(50 * t)}
    with open(d / "table.csv", "w") as fh:
        fh.write("t," + ",".join(cols) + "\n")
        for i in range(t.size):
            fh.write(",".join([repr(float(t[i]))] + [repr(float(v[i])) for v in cols.values()])
                     + "\n")
    (d / "scenario.json").write_text(json.dumps({"road": {"length_m": 4.0}, "fatigue": {}}))
    return d


def test_cli_findley_writes_life_plane_and_csv(run_dir: Path, capsys) -> None:
    from orchestrator.fatigue_cli import main

    assert main([str(run_dir), "--quiet", "--out", str(run_dir / "eq")]) == 0
    eq = json.loads((run_dir / "eq" / "summary.json").read_text())
    assert main([str(run_dir), "--quiet", "--equivalent", "findley",
                 "--out", str(run_dir / "cp")]) == 0
    assert "critical plane (findley, 50 hot spots" in capsys.readouterr().out
    s = json.loads((run_dir / "cp" / "summary.json").read_text())
    c = s["critical_plane"]
    assert s["config"]["critical_plane"] == "findley"
    assert s["config"]["equivalent"] == "abs_max_principal"
    assert s["equivalent_pass"]["min_life_km"] == eq["min_life_km"]
    assert 0 < s["min_life_km"] < math.inf and s["min_life_km"] == c["min_life_km"]
    rows = (run_dir / "cp" / "critical_plane.csv").read_text().splitlines()
    assert len(rows) == 51
    lives = [float(r.split(",")[14]) for r in rows[1:]]
    assert min(lives) == pytest.approx(s["min_life_km"], rel=1e-6)
    assert int(rows[1].split(",")[0]) == s["critical_node_id"]
    assert np.linalg.norm(c["normal"]) == pytest.approx(1.0)
    assert all(0.0 <= h["rotation_factor"] <= 1.0 + 1e-9 for h in c["hot_spots"])


def test_live_summary_says_the_planes_were_not_computed() -> None:
    from nodes.fatigue.config import FatigueConfig
    from nodes.fatigue.lib.result import FatigueResult
    from nodes.fatigue.run_dir import summary_dict

    cfg = FatigueConfig.from_dict({"equivalent": "findley"})
    assert (cfg.equivalent, cfg.critical_plane) == ("abs_max_principal", "findley")
    z = np.zeros(2)
    r = FatigueResult(damage=np.array([1e-3, 0.0]), node_ids=np.arange(2), node_xyz=None,
                      eq_max=z, eq_min=z, eq_range_max=z, n_cycles=z, track_length_m=1.0,
                      duration_s=1.0, n_samples=2, config=cfg.as_dict())
    assert summary_dict(r)["critical_plane"]["computed"] is False
