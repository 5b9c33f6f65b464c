"""``suscosim fatigue RUN_DIR --part PART.toml`` (#26 item 5): a part the project has never
seen (a STEP link made here, its joints on two of the arm's load channels) assessed under a
real run's loads, with no code change; the run's own fatigue results stay."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from orchestrator.cli import main as cli

from .test_part_user import LINK_MESH, make_link, write_part

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "thesis" / "ch6_realistic_qvm.toml"
JOINTS = """
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


def test_fatigue_of_a_run_on_a_users_part(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("SUSCOSIM_CACHE", str(tmp_path / "cache"))
    run = tmp_path / "run"
    assert cli(["run", str(SCENARIO), "--mode", "monolithic", "--quiet", "--out", str(run),
                "--set", "road.length_m=3", "--set", "fatigue.live=false"]) == 0
    make_link(tmp_path)
    part = write_part(tmp_path, extra=JOINTS, mesh=LINK_MESH)
    assert cli(["fatigue", str(run), "--part", str(part), "--quiet"]) == 0
    folders = sorted(run.glob("fatigue-*"))
    assert len(folders) == 1 and not (run / "fatigue").exists()  # a what-if, aside
    summary = json.loads((folders[0] / "summary.json").read_text())
    rows = np.genfromtxt(folders[0] / "damage_per_node.csv", delimiter=",", names=True)
    assert len(rows) == summary["n_nodes"] > 100  # the link's own mesh, not the arm's 2925
    assert np.isfinite(summary["min_life_km"]) and summary["min_life_km"] > 0
    assert (rows["damage_per_pass"] > 0).any()  # the run's ball-joint and bush loads reached it
    # a channel the part does not take is named, not dropped silently
    unmapped = {u["channel"] for u in summary["unmapped_channels"]}
    assert "plant/arm/ball_joint_x" in unmapped and "plant/arm/ball_joint_z" not in unmapped
    assert cli(["fatigue", str(run), "--part", str(tmp_path / "nope.toml")]) == 2
