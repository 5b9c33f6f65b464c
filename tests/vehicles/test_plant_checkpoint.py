"""Every plant model checkpoints and restores bit for bit (issue #29 item 4, the plant's part).

A model driven with random tyre and damper forces is checkpointed
(:meth:`nodes.plant.model.PlantModel.checkpoint_state`, as plain data as the checkpoint
store holds it), restored into a model built afresh from the same configuration, and both are driven
on with the same forces: their states and loads must be equal to the last bit. A fresh model
that is not restored must differ (else the test would prove nothing). One case restores in
another process, as ``--resume`` will.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from cosim import plaindata
from nodes.plant.models import build_plant_model

from ..conftest import ROOT

MODELS = {name: {"model": name} for name in (
    "quarter_car_lumped", "quarter_car_double_wishbone", "full_vehicle_7dof",
    "full_vehicle_double_wishbone")}
MODELS["full_vehicle_double_wishbone+driver"] = {  # the driver's speed and steering state
    "model": "full_vehicle_double_wishbone", "speed_kmh": 50.0,
    "driver": {"speed": [[0.0, 13.9], [0.1, 12.0]], "radius": 40.0}}


def drive(model, steps: int, seed: int) -> tuple[np.ndarray, dict]:
    """``steps`` substeps of 0.5 ms with random forces; the states stacked, the last loads."""
    rng = np.random.default_rng(seed)
    n, static = model.n_corners, model.static_tyre_load()
    rows, loads = [], {}
    for _ in range(steps):
        if hasattr(model, "set_tyre_forces"):  # the Magic Formula's in-plane forces (#31)
            model.set_tyre_forces(1500.0 * rng.standard_normal(n), 1500.0 * rng.standard_normal(n),
                                  20.0 * rng.standard_normal(n))
        model.substep(0.0005, static * (1 + 0.2 * rng.standard_normal(n)),
                      300.0 * rng.standard_normal(n))
        rows.append(np.concatenate([np.ravel(v) for v in model.state().values()]))
        loads = model.loads()
    return np.array(rows), loads


@pytest.mark.parametrize("name", MODELS)
def test_a_restored_model_continues_bit_for_bit(name: str) -> None:
    cfg = MODELS[name]
    a = build_plant_model(cfg)
    b = build_plant_model(cfg)
    fresh = build_plant_model(cfg)
    try:
        drive(a, 300, seed=1)
        b.restore_state(plaindata.decode(plaindata.encode(a.checkpoint_state())))
        xa, la = drive(a, 300, seed=2)
        xb, lb = drive(b, 300, seed=2)
        xf, _ = drive(fresh, 300, seed=2)
        assert np.array_equal(xa, xb) and la == lb
        assert not np.array_equal(xa, xf)
    finally:
        for m in (a, b, fresh):
            m.close()


def test_a_checkpoint_of_another_model_is_refused() -> None:
    a = build_plant_model({"model": "quarter_car_lumped"})
    b = build_plant_model({"model": "full_vehicle_7dof"})
    try:
        with pytest.raises(ValueError, match="quarter_car_lumped"):
            b.restore_state(a.checkpoint_state())
    finally:
        a.close()
        b.close()


_CHILD = textwrap.dedent("""
    import sys
    import numpy as np
    sys.path.insert(0, {root!r})
    from cosim import plaindata
    from nodes.plant.models import build_plant_model
    from tests.vehicles.test_plant_checkpoint import drive
    model = build_plant_model({{"model": "quarter_car_double_wishbone"}})
    if sys.argv[1] == "save":
        drive(model, 300, seed=1)
        with open(sys.argv[2], "wb") as f:
            f.write(plaindata.encode(model.checkpoint_state()))
    else:
        with open(sys.argv[2], "rb") as f:
            model.restore_state(plaindata.decode(f.read()))
    x, _ = drive(model, 300, seed=2)
    np.save(sys.argv[3], x)
""")


def test_the_realistic_corner_resumes_in_another_process(tmp_path) -> None:
    script = tmp_path / "child.py"
    script.write_text(_CHILD.format(root=str(ROOT)))
    ckpt, run_on, resumed = tmp_path / "c.pkl", tmp_path / "a.npy", tmp_path / "b.npy"
    for args in (("save", ckpt, run_on), ("load", ckpt, resumed)):
        res = subprocess.run([sys.executable, str(script), *map(str, args)], cwd=ROOT,
                             capture_output=True, text=True, timeout=120)
        assert res.returncode == 0, res.stderr
    assert np.array_equal(np.load(run_on), np.load(resumed))
