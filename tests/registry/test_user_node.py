"""A user's own node, named in a scenario's ``[nodes]``, runs in a real distributed run (one
process per node, real Zenoh on loopback): its forces are what the plant applies and what
the table records."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from cosim import node_kinds as nk
from cosim import scenario as sc
from cosim.errors import ScenarioError
from cosim.table import read_table
from orchestrator.runner import resolve, run_scenario

from ..conftest import CH3_STEP, ROOT

pytestmark = pytest.mark.integration

C = 1234.5  # N s/m: not the scenario's 1500, so the table shows whose damper it was

USER_NODES = textwrap.dedent(f'''
    """A user's controller node, outside the suscosim packages."""
    import numpy as np


    class LinearDamper:
        """F_d = c (v_w - v_b) [N], c = {C} N s/m; a stepped node (cosim/stepped.py)."""

        @staticmethod
        def preflight(scenario, facts):
            assert facts["n_corners"] == 1

        def __init__(self, scenario, start):
            self.c = {C}
            self.n_corners = start["info"]["plant"]["n_corners"]

        def step(self, k, t, inputs):
            s = inputs["plant/state"]
            v_rel = s["v_w"] - s["v_b"]
            return {{"F_d": self.c * v_rel, "c_eff": np.full_like(v_rel, self.c),
                     "user_step": float(k)}}


    def linear_damper(part, scenario):
        """The same damper as a function entry: the node's whole shell is its own."""
        part.output("force")
        state = part.listen("plant", "state", required=("v_b", "v_w"))
        start = part.handshake(timeout_s=scenario["run"]["start_timeout_s"])
        n, h = int(start["n_steps"]), scenario["run"]["h"]
        for k in range(n + 1):
            s = part.wait({{state: k}})[state]
            v_rel = s.array("v_w") - s.array("v_b")
            part.publish("force", k, k * h, {{"F_d": {C} * v_rel, "c_eff": {C},
                                              "user_step": float(k)}})
        part.finish(n, n * h)
''')


@pytest.fixture
def user_module(tmp_path: Path, monkeypatch) -> str:
    """A module in a folder of its own, on PYTHONPATH (for the node processes) and on
    sys.path (for the orchestrator's preflight)."""
    folder = tmp_path / "user_code"
    folder.mkdir()
    (folder / "my_dampers.py").write_text(USER_NODES)
    monkeypatch.setenv("PYTHONPATH", f"{folder}:{ROOT}")
    monkeypatch.syspath_prepend(str(folder))
    return "my_dampers"


def _run(tmp_path: Path, entry: str, mode: str) -> dict:
    scenario = sc.load(CH3_STEP, ["run.t_end=0.6", f'run.mode="{mode}"'])
    scenario[nk.SECTION] = {"controller": entry}
    resolved = resolve(scenario, tmp_path / "run")
    summary = run_scenario(resolved, quiet=True)
    assert summary["status"] == "ok", summary
    return read_table(tmp_path / "run" / "table.parquet")


def _assert_user_forces(table: dict) -> None:
    n = len(table["t"])
    assert n == 601
    assert np.array_equal(table["controller/force/user_step"], np.arange(n, dtype=float))
    v_rel = table["plant/state/v_w"] - table["plant/state/v_b"]
    assert np.max(np.abs(v_rel)) > 0.01  # the step moves the car
    assert np.array_equal(table["controller/force/F_d"], C * v_rel)
    assert np.all(table["controller/force/c_eff"] == C)
    # the plant applied them (its own record of the force at t_k)
    assert np.array_equal(table["plant/response/F_d"], table["controller/force/F_d"])


def test_a_user_controller_class_runs_distributed(tmp_path: Path, user_module: str) -> None:
    """Through the CLI, as a user does: ``[nodes]`` in the scenario file, ``suscosim run``."""
    path = tmp_path / "mine.toml"
    path.write_text(CH3_STEP.read_text()
                    + f'\n[nodes]\ncontroller = "{user_module}:LinearDamper"\n')
    res = subprocess.run([sys.executable, "-m", "orchestrator", "run", str(path), "--out",
                          str(tmp_path / "run"), "--quiet", "--set", "run.t_end=0.6"],
                         cwd=tmp_path, env=dict(os.environ), capture_output=True, text=True,
                         timeout=180)
    assert res.returncode == 0, res.stdout + res.stderr
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["mode"] == "distributed" and summary["nodes"] == list(nk.always())
    _assert_user_forces(read_table(tmp_path / "run" / "table.parquet"))


def test_a_user_controller_class_runs_in_process(tmp_path: Path, user_module: str) -> None:
    """The one-process engine steps a user's class as it steps the kind's own (#41)."""
    _assert_user_forces(_run(tmp_path, f"{user_module}:LinearDamper", "monolithic"))


def test_a_user_controller_function_runs_distributed_and_is_refused_in_process(
        tmp_path: Path, user_module: str) -> None:
    """A function node is written against the bus: the in-process engine says so (exit 2)."""
    _assert_user_forces(_run(tmp_path, f"{user_module}:linear_damper", "distributed"))
    with pytest.raises(ScenarioError, match="stepped class with run.transport"):
        _run(tmp_path / "in", f"{user_module}:linear_damper", "monolithic")
