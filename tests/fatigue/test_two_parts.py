"""Two parts in one run (#26 item 5): ``[fatigue] parts = [<the upper arm>]`` beside the primary
part, a distributed run (real processes over Zenoh) with the live fatigue node, whose results
for both parts equal the batch ``suscosim fatigue RUN_DIR``'s bit for bit; a part the project
has never seen (a STEP made here) on the upper arm's channels through ``suscosim part check``
and ``suscosim fatigue RUN_DIR --part``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import ROOT, suscosim

from .test_part_user import LINK_MESH, make_link, write_part

SCENARIO = ROOT / "scenarios" / "thesis" / "ch6_realistic_qvm.toml"
UPPER = ROOT / "nodes" / "fatigue" / "parts" / "data" / "upper_arm.toml"
ARM_JOINTS = """
[[joint]]
name = "ball"
centre = [0.0, 0.0, 0.0]
axis = [0, 0, 1]
radius = 0.0105
length = 0.05
forces = { z = "ball_joint_z" }

[[joint]]
name = "bush"
centre = [0.2, 0.0, 0.0]
axis = [0, 0, 1]
radius = 0.0105
length = 0.05
forces = { x = "bush_front_x", z = "bush_front_z" }
"""
UPPER_JOINTS = """
[[joint]]
name = "ball"
centre = [0.0, 0.0, 0.0]
axis = [0, 0, 1]
radius = 0.0105
length = 0.05
forces = { x = "upper_ball_joint_x", y = "plant/upper_arm/upper_ball_joint_y" }

[[joint]]
name = "bush"
centre = [0.2, 0.0, 0.0]
axis = [0, 0, 1]
radius = 0.0105
length = 0.05
forces = { x = "upper_bush_front_x", y = "upper_bush_front_y" }
"""


def _coarse_upper_arm(folder: Path) -> Path:
    """The shipped upper arm's part file at a 14 mm mesh (a fast solve), its STEP the shipped."""
    text = UPPER.read_text().replace('geometry = "upper_arm.step"',
                                     f'geometry = "{UPPER.with_suffix(".step")}"')
    text = text.replace("size = 0.008 ", "size = 0.014 ")
    assert "size = 0.014" in text
    path = folder / "upper_arm.toml"
    path.write_text(text)
    return path


@pytest.mark.integration
def test_two_parts_live_equal_batch_and_a_users_upper_arm_part(tmp_path, monkeypatch):
    from nodes.fatigue.parts import load_part
    from nodes.fatigue.parts.build import part_influence

    # the processes the test starts inherit the cache
    monkeypatch.setenv("SUSCOSIM_CACHE", str(tmp_path / "cache"))
    make_link(tmp_path)
    link = write_part(tmp_path, extra=ARM_JOINTS, mesh=LINK_MESH)
    upper = _coarse_upper_arm(tmp_path)
    for p in (link, upper):  # solved here once: the fatigue node then starts from the cache
        part_influence(load_part(p))
    run = tmp_path / "run"
    res = suscosim("run", str(SCENARIO), "--mode", "distributed", "--quiet", "--out", str(run),
                   "--set", "road.length_m=3", "--set", "fatigue.block_samples=97",
                   "--set", f'fatigue.influence="{link}"', "--set", "fatigue.screen=0",
                   "--set", f'fatigue.parts=["{upper}"]', timeout=300)  # unscreened:
    # every node live == batch, byte for byte (screened: tests/fatigue/test_live_node.py)
    assert res.returncode == 0, res.stdout + res.stderr
    run_summary = json.loads((run / "summary.json").read_text())
    assert run_summary["fatigue"]["parts"]["upper_arm"]["files"] == str(run / "fatigue"
                                                                        / "upper_arm")
    live = json.loads((run / "fatigue" / "summary.json").read_text())
    assert live["source"] == "live"
    names = [(p["name"], p["load_channel"]) for p in live["parts"]]
    assert names == [("link", "plant/arm"), ("upper_arm", "plant/upper_arm")]
    live_ua = json.loads((run / "fatigue" / "upper_arm" / "summary.json").read_text())
    assert live_ua["source"] == "live" and live_ua["n_nodes"] > 500
    assert live_ua["n_samples"] == live["n_samples"] == run_summary["n_steps"] + 1
    assert 0 < live_ua["max_damage_per_pass"] and np.isfinite(live_ua["min_life_km"])
    assert not live_ua["missing_channels"]  # every upper-arm case had its load
    # the batch on the recorded table: both parts, the same bits
    batch = tmp_path / "batch"
    res = suscosim("fatigue", str(run), "--out", str(batch), timeout=300)
    assert res.returncode == 0, res.stderr
    assert "part upper_arm (plant/upper_arm)" in res.stdout
    for sub in (".", "upper_arm"):
        assert (run / "fatigue" / sub / "damage_per_node.csv").read_bytes() == \
            (batch / sub / "damage_per_node.csv").read_bytes(), sub
    b = json.loads((batch / "summary.json").read_text())
    assert [p["min_life_km"] for p in b["parts"]] == [p["min_life_km"] for p in live["parts"]]
    assert (batch / "upper_arm" / "sn_plot.png").is_file()  # the batch outputs, per part
    # the upper arm alone through --part: the same damage as in the two-part analysis
    alone = tmp_path / "alone"
    res = suscosim("fatigue", str(run), "--part", str(upper), "--out", str(alone),
                   "--quiet")
    assert res.returncode == 0, res.stderr
    assert (alone / "damage_per_node.csv").read_bytes() == \
        (batch / "upper_arm" / "damage_per_node.csv").read_bytes()
    # a part the project has never seen, on the upper arm's loads (short and full channel
    # names): part check, then fatigue --part, no code change
    other = tmp_path / "other"
    other.mkdir()
    make_link(other)
    user = write_part(other, extra=UPPER_JOINTS, mesh=LINK_MESH)
    res = suscosim("part", "check", str(user), "--json", "--mesh-size", "0.02")
    assert res.returncode == 0, res.stderr
    assert set(json.loads(res.stdout)["joints"]) == {"ball", "bush"}
    res = suscosim("fatigue", str(run), "--part", str(user), "--out", str(tmp_path / "u"),
                   "--quiet")
    assert res.returncode == 0, res.stderr
    s = json.loads((tmp_path / "u" / "summary.json").read_text())
    assert s["n_nodes"] > 100 and not s["missing_channels"]
    assert 0 < s["max_damage_per_pass"] and np.isfinite(s["min_life_km"])
    unmapped = {u["channel"] for u in s["unmapped_channels"]}
    assert "upper_bush_rear_z" in unmapped and "upper_ball_joint_x" not in unmapped
