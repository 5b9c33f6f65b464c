"""#31 over the bus: the four-corner vehicle's 3-D tyre forces cross from the tyre/road node
to the plant in a distributed run (real node processes, real Zenoh). Before the plant took
Fx/Fy/Mz from the tyre/road message, the brakes locked the wheels and the car did not slow."""

from __future__ import annotations

import numpy as np
import pytest

from cosim.table import read_table
from tests.conftest import ROOT, suscosim

pytestmark = pytest.mark.integration

BRAKING = ROOT / "scenarios" / "events" / "braking_50kmh_0p8g.toml"


def test_braking_decelerates_the_vehicle_through_the_tyre_node_s_fx(tmp_path) -> None:
    out = tmp_path / "run"
    res = suscosim("run", str(BRAKING), "--out", str(out), "--quiet",
                   "--set", "run.t_end=1.0", "--set", "fatigue.live=false", timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    t = read_table(out / "table.parquet")
    time, u = t["t"], t["plant/state/u"]
    Fx = np.stack([t[f"tyre_road/force/Fx[{i}]"] for i in range(4)], axis=1)
    late = (time > 0.6) & (time < 0.95)  # the driver's ramp: 13.89 -> 2 m/s over 0.3..1.815 s
    a_x = np.polyfit(time[late], u[late], 1)[0]
    assert a_x == pytest.approx(-11.8889 / 1.515, rel=0.10)  # 0.8 g
    front = Fx[late, :2].sum(axis=1).mean()
    total = Fx[late].sum(axis=1).mean()
    assert total < 0
    assert front / total == pytest.approx(0.72, abs=0.05)  # the brake balance
    assert np.allclose(Fx[late, 0], Fx[late, 1], rtol=0.05)  # left = right on a flat road
