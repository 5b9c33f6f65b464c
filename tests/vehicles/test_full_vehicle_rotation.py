"""The 7-DOF full vehicle's body pitch and roll accelerations (``alpha_pitch``,
``alpha_roll`` in ``plant/response``; thesis Tables 5.7-5.10): the rate of change of the
pitch and roll rates, with the signs of the model's axes, and published by the plant node."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from cosim.table import read_table
from nodes.plant.full_vehicle_7dof import FullVehicle7DOF

from ..conftest import ROOT, suscosim

DT = 1e-3


def test_pitch_and_roll_accelerations_integrate_to_the_rates():
    """A 2 kN push up under the front-left wheel only: the nose rises (pitch, positive nose
    down, accelerates negative) and the left side rises (roll, positive left up, accelerates
    positive); the accelerations summed over the substeps give the rates."""
    m = FullVehicle7DOF()
    try:
        W = m.static_tyre_load()
        push = W + np.array([2000.0, 0.0, 0.0, 0.0])
        acc = []
        for _ in range(300):
            v0 = m.response_velocities()
            m.substep(DT, push, np.zeros(4))
            v1 = m.response_velocities()
            acc.append([float((v1[k] - v0[k])[0]) / DT for k in ("alpha_pitch", "alpha_roll")])
        st = m.state()
    finally:
        m.close()
    acc = np.array(acc)
    np.testing.assert_allclose(acc.sum(axis=0) * DT, [st["w_pitch"][0], st["w_roll"][0]],
                               rtol=1e-9, atol=1e-12)
    assert acc[:100, 0].mean() < -1e-3 and acc[:100, 1].mean() > 1e-3


def test_the_plant_node_publishes_them(tmp_path: Path):
    out = tmp_path / "run"
    res = suscosim("run", str(ROOT / "scenarios" / "ch4_fvm_random.toml"), "--out", str(out),
                   "--mode", "monolithic", "--quiet", "--set", "run.t_end=1.0")
    assert res.returncode == 0, res.stderr + res.stdout
    assert json.loads((out / "summary.json").read_text())["status"] == "ok"
    table = read_table(out / "table.parquet")
    t = np.asarray(table["t"], dtype=float)
    for name, rate in (("alpha_pitch", "w_pitch"), ("alpha_roll", "w_roll")):
        a = np.asarray(table[f"plant/response/{name}"], dtype=float)
        w = np.asarray(table[f"plant/state/{rate}"], dtype=float)
        assert np.sqrt(np.mean(a ** 2)) > 0.01
        # the first-substep rate against the steps' central difference of the state rate
        # (agree to the step's change of the acceleration)
        dw = np.gradient(w, t)
        err = np.sqrt(np.mean((a[5:-5] - dw[5:-5]) ** 2)) / np.sqrt(np.mean(dw[5:-5] ** 2))
        assert err < 0.15  # 0.06 on this road
