"""Corner files (cosim/corner.py): the built-in one is today's corner bit for bit, bad files
are refused naming the key, another corner builds the PyBullet corner and the CLI."""

from __future__ import annotations

import copy
import json
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from cosim import corner as cf
from cosim import lower_arm as la
from cosim.errors import InputFileError, ScenarioError
from nodes.plant.models import build_plant_model
from orchestrator.studies import corner_check

WIDE = Path(__file__).with_name("corners") / "wide_track.toml"
ROOT = Path(__file__).resolve().parents[2]


def _builtin_dict() -> dict:
    return tomllib.loads(cf.BUILTIN.read_text(encoding="utf-8"))


def test_builtin_arm_hardpoints_are_the_numbers_the_fe_had():
    # the arm-frame points cosim.lower_arm had as literals before they came from the file:
    # the same doubles (the FE's unit-load cases and its cache key depend on them)
    old = {"bush_front": [0.130, 0.0, 0.0], "bush_rear": [-0.130, 0.0, 0.0],
           "ball_joint": [0.025, 0.294, 0.0], "damper_mount": [0.064, 0.185, 0.0],
           "bump_stop": [-0.017, 0.215, 0.0]}
    for name, v in old.items():
        assert la.HARDPOINTS[name].tobytes() == np.array(v).tobytes(), name
    assert la.ARM_ORIGIN.tobytes() == np.array([0.0, -0.06 - 0.294, -0.13]).tobytes()
    assert la.lever_ball_joint() == 0.294


def test_vehicle_origin_points_give_the_same_corner():
    d = _builtin_dict()
    wc = np.array([0.1, 0.7055, 0.30])
    d["frame"] = {"reference": "vehicle", "tyre_loaded_radius": 0.30}
    d["hardpoints"] = {k: (np.array(v) + wc).tolist() for k, v in d["hardpoints"].items()}
    d["hardpoints"]["wheel_centre"] = wc.tolist()
    c, b = cf.from_dict(d), cf.builtin()
    assert c.half_track == 0.7055
    for k in b.points:
        assert np.allclose(c.points[k], b.points[k], atol=1e-15), k


@pytest.mark.parametrize("edit, key", [
    (lambda d: d["hardpoints"].pop("upper_ball_joint"), "hardpoints.upper_ball_joint"),
    (lambda d: d["hardpoints"].__setitem__("lower_ball_joint", [0.025, -0.5, -0.13]),
     "hardpoints.lower_ball_joint"),  # inboard of its bushes: a right-hand corner
    (lambda d: d["hardpoints"].__setitem__("tie_rod_outer", [1, 2]), "hardpoints.tie_rod_outer"),
    (lambda d: d["masses"].__setitem__("hub", -1.0), "masses.hub"),
    (lambda d: d["spring"].__setitem__("coil_n_per_m", 2e4), "hardpoints.spring_lower"),
    (lambda d: d["bump_stop"].__setitem__("clerance", 0.04), "bump_stop.clerance"),
    (lambda d: d["frame"].__setitem__("reference", "ground"), "frame.reference"),
    (lambda d: d.__setitem__("version", 2), "version"),
])
def test_a_bad_corner_file_is_refused_naming_the_key(tmp_path, edit, key):
    d = copy.deepcopy(_builtin_dict())
    edit(d)
    with pytest.raises(ScenarioError) as e:
        cf.from_dict(d)
    assert e.value.key == key


def test_corner_check_cli_on_a_bad_file_exits_2_naming_file_and_key(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(cf.BUILTIN.read_text().replace("hub = 38.75", "hub = -38.75"))
    assert corner_check.main(["check", str(bad)]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and "masses.hub" in err and "Traceback" not in err
    assert corner_check.main(["check", str(tmp_path / "missing.toml")]) == 2
    with pytest.raises(InputFileError, match="not valid TOML"):
        (tmp_path / "x.toml").write_text("[hardpoints\n")
        cf.load(tmp_path / "x.toml")


def test_corner_check_json_of_another_corner(capsys):
    assert corner_check.main(["check", str(WIDE), "--json", "--points", "5"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["corner"] == "wide_track" and r["half_track_m"] == 0.78
    cv = r["curves"]
    assert len(cv["z_w"]) == 5 and np.allclose(cv["z_w"], np.linspace(-0.08, 0.08, 5))
    eq = r["equivalent_quarter_car"]
    assert eq["m_s"] == 560.0 and eq["m_u"] == pytest.approx(49.7)
    # its own lever: K_theta / z'^2 with z' ~ its 0.32 m ball-joint lever (a little more:
    # the wheel centre is further from the instant centre than the ball joint)
    k_lever = 57.0 * 180.0 / np.pi / 0.32 ** 2
    assert 0.93 * k_lever < r["ride_height"]["wheel_rate_elastic_n_per_m"] < k_lever


def test_another_corner_builds_the_pybullet_corner_in_equilibrium():
    m = build_plant_model({"model": "quarter_car_double_wishbone", "corner": str(WIDE)})
    try:
        info = m.info()
        assert info["corner"] == "wide_track"
        hp = la.hardpoints_of(cf.load(WIDE))
        assert np.allclose(info["arm_points"]["ball_joint"], hp["ball_joint"], atol=1e-12)
        assert hp["ball_joint"][1] == pytest.approx(0.32)
        assert m.static_tyre_load()[0] == pytest.approx((560.0 + 49.7) * 9.81)
        W = m.static_tyre_load()
        for _ in range(200):  # at the static load it stays where it was built
            m.substep(1e-3, W, np.array([3600.0 * m.state()["v_damper"][0]]))
        st = m.state()
        assert abs(st["z_w"][0]) < 1e-6 and abs(st["z_b"][0]) < 1e-6
        for _ in range(200):  # 1 kN more: the spring force uses this corner's lever
            m.substep(1e-3, W + 1000.0, np.array([3600.0 * m.state()["v_damper"][0]]))
        dtheta = float(m.state()["arm_angle"][0])
        assert float(m.spring_force()[0]) == pytest.approx(
            57.0 * 180.0 / np.pi * dtheta / hp["ball_joint"][1], rel=1e-9)
    finally:
        m.close()


def test_scenario_keys_override_the_corner_file_and_bad_ones_are_named():
    m = build_plant_model({"model": "quarter_car_double_wishbone", "corner": str(WIDE),
                           "body_mass": 600.0, "bump_stop": False})
    try:
        assert m.params.body_mass == 600.0 and m.params.hub_mass == 40.0
        assert m.bump_stop is None
    finally:
        m.close()
    with pytest.raises(InputFileError, match="nope.toml"):
        build_plant_model({"model": "quarter_car_double_wishbone", "corner": "/nope.toml"})
    with pytest.raises(ScenarioError) as e:
        build_plant_model({"model": "quarter_car_double_wishbone", "corner": 3})
    assert e.value.key == "vehicle.corner"


def test_a_coil_spring_corner_is_refused_by_the_pybullet_corner(tmp_path):
    text = cf.BUILTIN.read_text().replace(
        "torsion_bar_nm_per_deg = 46.74", "torsion_bar_nm_per_deg = 46.74\ncoil_n_per_m = 2e4")
    text = text.replace("\n[hardpoints]\n", "\n[hardpoints]\nspring_lower = [0.0, -0.2, -0.13]\n"
                        "spring_upper = [0.0, -0.2, 0.3]\n")
    f = tmp_path / "coil.toml"
    f.write_text(text)
    with pytest.raises(ScenarioError, match="no coil spring yet") as e:
        build_plant_model({"model": "quarter_car_double_wishbone", "corner": str(f)})
    assert e.value.key == "vehicle.corner"


def test_importing_the_plant_prints_no_pybullet_banner():
    r = subprocess.run([sys.executable, "-c", "import nodes.plant.double_wishbone"],
                       cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert r.returncode == 0
    assert "pybullet build time" not in r.stdout + r.stderr


def test_a_copy_of_the_builtin_file_builds_the_same_corner(tmp_path):
    from nodes.plant.double_wishbone import DoubleWishboneParams
    from nodes.plant.double_wishbone_geometry import BUILTIN, CornerGeometry

    copy_ = tmp_path / "mine.toml"
    copy_.write_text(cf.BUILTIN.read_text())
    g = CornerGeometry(cf.load(copy_))
    # the same lower arm is the FE part wherever the file lives (and mirrored, too)
    assert g.fe_arm and CornerGeometry(cf.builtin().mirrored()).fe_arm
    assert g.urdf(DoubleWishboneParams()) == BUILTIN.urdf(DoubleWishboneParams())
    assert not CornerGeometry(cf.load(WIDE)).fe_arm
