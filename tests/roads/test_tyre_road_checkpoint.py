"""The tyre/road node checkpoints and restores bit for bit (issue #29 item 4, its part).

The four-corner vehicle with Magic Formula tyres (relaxation states, the path's origin) is
run closed loop with the tyre/road node's stepped class for 100 steps; plant and tyre/road
are checkpointed, restored into a pair built afresh from the scenario, and both pairs run
100 steps more: the tyre forces must be equal to the last bit, and a tyre/road node that
was not restored must give other ones.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from cosim import plaindata
from cosim import scenario as sc
from nodes.plant.models import build_plant_model
from nodes.tyre_road.node import TyreRoad

ROOT = Path(__file__).resolve().parents[2]
CORNERING = ROOT / "scenarios" / "events" / "cornering_0p5g.toml"
H = 0.002


def _pair(scenario):
    plant = build_plant_model(scenario["vehicle"])
    return plant, TyreRoad(scenario, {"info": {"plant": plant.info()}})


def _run(plant, tyre, k0: int, steps: int) -> np.ndarray:
    out = []
    for k in range(k0, k0 + steps):
        f = tyre.step(k, k * H, {"plant/state": plant.state()})
        plant.set_tyre_forces(f["Fx"], f["Fy"], f["Mz"])
        for _ in range(4):
            plant.substep(H / 4, f["F_t"], np.zeros(plant.n_corners))
        out.append(np.concatenate([np.ravel(f[k]) for k in ("F_t", "Fx", "Fy", "Mz")]))
    return np.array(out)


def test_the_magic_formula_tyre_road_node_resumes_bit_for_bit() -> None:
    scenario = sc.load(CORNERING)
    plant_a, tyre_a = _pair(scenario)
    plant_b, tyre_b = _pair(scenario)
    plant_c, tyre_c = _pair(scenario)
    try:
        _run(plant_a, tyre_a, 0, 100)
        saved = plaindata.decode(plaindata.encode((plant_a.checkpoint_state(),
                                           tyre_a.checkpoint_state())))
        plant_b.restore_state(saved[0])
        tyre_b.restore_state(saved[1])
        plant_c.restore_state(saved[0])  # the plant restored, the tyre/road node not
        a, b, c = (_run(p, t, 100, 100) for p, t in
                   ((plant_a, tyre_a), (plant_b, tyre_b), (plant_c, tyre_c)))
        assert np.array_equal(a, b)
        assert not np.array_equal(a, c)
        assert np.abs(a[:, 8:12]).max() > 1000.0  # cornering: lateral tyre forces flow
    finally:
        for p in (plant_a, plant_b, plant_c):
            p.close()
