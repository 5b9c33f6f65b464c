"""#30 item 5: pseudo-damage of load channels equals the hand calculation; two sources side
by side (``suscosim pseudo-damage``) give the ratio of the hand values."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from nodes.fatigue.lib.counting import count_series
from nodes.fatigue.lib.pseudo_damage import pseudo_damage, rainflow_matrix
from orchestrator.pseudo_damage_cli import main


def test_hand_calculation() -> None:
    # 0 -> 2000 -> 0 -> 1000 -> 0 N: ASTM half cycles 2000 (x2: up and down),
    # the inner 0-1000-0 is a full cycle of range 1000, ... count it with the counter
    x = np.array([0.0, 2000.0, 1000.0, 1500.0, 0.0])
    cyc = count_series(x, "half_cycles")
    # by hand (ASTM E1049 rainflow): full cycle 1000-1500 (range 500), half cycles
    # 0-2000 and 2000-0 (range 2000 each)
    ranges = sorted(zip(cyc.range.tolist(), cyc.count.tolist(), strict=True))
    assert ranges == [(500.0, 1.0), (2000.0, 0.5), (2000.0, 0.5)]
    hand = (1.0 * 0.5**5 + 0.5 * 2.0**5 + 0.5 * 2.0**5) / 1e6
    assert pseudo_damage(cyc, 5.0, 1000.0, 1e6) == pytest.approx(hand, rel=1e-14)
    m = rainflow_matrix(cyc, n_bins=4)
    assert np.sum(m["counts"]) == pytest.approx(2.0)


def test_two_sources_side_by_side(tmp_path: Path, capsys) -> None:
    t = np.arange(21) * 0.01
    a = tmp_path / "sim.csv"
    b = tmp_path / "rig.csv"
    # -A, A, -A, ... (21 turning points): 20 reversals of range 2A = 10 cycles;
    # A = 1 kN (range 2 kN) against 1.5 kN (range 3 kN)
    for f, amp in ((a, 1000.0), (b, 1500.0)):
        y = amp * np.where(np.arange(21) % 2 == 0, -1.0, 1.0)
        f.write_text("t,Fz\n" + "".join(f"{float(x)!r},{float(v)!r}\n"
                                         for x, v in zip(t, y, strict=True)))
    capsys.readouterr()
    assert main([str(a), str(b), "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    sim, rig = res["channels"]["Fz"]
    # hand: 10 cycles of range 2 kN: D = 10 x 2^5 / 1e6; the rig's: 10 x 3^5 / 1e6
    assert sim["cycles"] == 10.0
    assert sim["pseudo_damage"] == pytest.approx(10 * 2.0**5 / 1e6, rel=1e-12)
    assert rig["pseudo_damage"] == pytest.approx(10 * 3.0**5 / 1e6, rel=1e-12)
    assert sim["equivalent_range"] == pytest.approx(1000 * (10 * 2.0**5 / 1e6) ** 0.2)
    assert rig["ratio_to_first"] == pytest.approx(1.5**5, rel=1e-9)
    assert main([str(a), str(tmp_path / "nowhere.csv")]) == 2
