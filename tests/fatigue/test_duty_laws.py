"""#31 item 3: a duty cycle under several damper laws (``[[laws]]`` in the duty file): every
scenario event run under each law, each law's schedule summed, and the event x law table at
the reference law's critical node (orchestrator/duty.py, nodes/fatigue/lib/duty_cycle.py). Short:
two four-corner events of 0.1 and 0.3 s (50 and 150 steps) under two laws, monolithic."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest

from nodes.fatigue.lib.duty_cycle import Event, law_matrix, schedule_damage

from ..conftest import COARSE_ARM, ROOT, suscosim

BRAKING = ROOT / "scenarios" / "events" / "braking_50kmh_0p8g.toml"
KERB = ROOT / "scenarios" / "events" / "kerb_strike_20kmh.toml"
KERB_EARLY = ('road.events=[{type = "bump", height = 0.10, length = 0.25, x_start = 0.2, '
              'tracks = "left"}]')  # the front-left wheel on the kerb at 0.04-0.08 s


def test_law_matrix_compares_every_law_at_the_reference_s_critical_node() -> None:
    ref = schedule_damage([Event("a", np.array([1e-6, 3e-6]), 10.0, 2),
                           Event("b", np.array([2e-6, 1e-6]), 5.0, 1)])  # node 1 critical
    other = schedule_damage([Event("a", np.array([9e-6, 1e-6]), 10.0, 2),
                             Event("b", np.array([1e-6, 1e-6]), 5.0, 1)])  # node 0 its own
    c, D = law_matrix([ref, other])
    assert c == 1
    np.testing.assert_allclose(D, [[6e-6, 1e-6], [2e-6, 1e-6]])
    with pytest.raises(ValueError, match="events"):
        law_matrix([ref, schedule_damage([Event("x", np.ones(2), 1.0, 1),
                                          Event("b", np.ones(2), 1.0, 1)])])


def _duty(tmp_path: Path, laws: str, events: str | None = None) -> Path:
    d = tmp_path / "duty.toml"
    d.write_text(events or f"""
[duty]
name = "laws"
[[events]]
name = "braking"
scenario = "{BRAKING}"
set = ["run.t_end=0.1", "fatigue.influence={COARSE_ARM}"]
repeats = 10
[[events]]
name = "kerb"
scenario = "{KERB}"
set = ["run.t_end=0.3", "fatigue.influence={COARSE_ARM}", {KERB_EARLY!r}]
repeats = 5
""" + laws)
    return d


@pytest.mark.integration
def test_each_event_runs_under_each_law_and_the_table_compares_them(tmp_path: Path) -> None:
    duty = _duty(tmp_path, """
[[laws]]
name = "passive"
[[laws]]
name = "hard"
set = ['controller = {law = "passive", c = 7600.0, velocity = "damper"}']
""")
    out = tmp_path / "out"
    res = suscosim("duty", str(duty), "--out", str(out), "--mode", "monolithic",
                   timeout=600)
    assert res.returncode == 0, res.stdout + res.stderr
    # each law's runs carry its controller
    for law, c in (("passive", 3800.0), ("hard", 7600.0)):
        for ev in ("braking", "kerb"):
            sc = json.loads((out / "runs" / law / ev / "scenario.json").read_text())
            assert sc["controller"]["c"] == c
        assert (out / "laws" / law / "duty.json").is_file()
    top = json.loads((out / "duty.json").read_text())
    laws = top["laws"]
    assert laws["reference"] == "passive" and laws["events"] == ["braking", "kerb"]
    # the reference's column is the top-level schedule's (the first law's: out/ itself)
    ref, hard = laws["laws"]
    assert ref["damage_per_schedule_at_node"] == pytest.approx(
        [e["damage_per_schedule_at_critical"] for e in top["events"]], rel=1e-12)
    assert laws["node_id"] == top["critical_node_id"]
    assert ref["ratio_to_reference"] == [1.0, 1.0]
    # twice the damping loads the arm harder over the kerb (the law reached the plant;
    # measured x2.7 on the hand-meshed arm the events are pinned to; on the CAD arm the
    # passive critical node is elsewhere and the hard law's kerb damage there is x0.27, a
    # result of that arm, not a check of the wiring); braking for 0.1 s hardly moves the dampers
    assert hard["ratio_to_reference"][1] > 1.5
    hard_own = json.loads((out / "laws" / "hard" / "duty.json").read_text())
    assert hard["life_km"] == hard_own["life_km"]
    with open(out / "laws.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [(r["law"], r["event"]) for r in rows] == [
        ("passive", "braking"), ("passive", "kerb"), ("hard", "braking"), ("hard", "kerb")]
    assert float(rows[3]["ratio_to_reference"]) == pytest.approx(hard["ratio_to_reference"][1])
    assert "by law" in res.stdout and "hard" in res.stdout
    # the report's page shows the table
    html = tmp_path / "duty.html"
    rep = suscosim("report", str(out), "--out", str(html), timeout=300)
    assert rep.returncode == 0, rep.stdout + rep.stderr
    text = html.read_text()
    assert 'id="laws"' in text and "hard" in text


@pytest.mark.parametrize("laws, match", [
    ('[[laws]]\nname = "a"\n[[laws]]\nname = "a"\n', "laws\\[1\\].name"),
    ('[[laws]]\nname = "a"\nc = 1\n', "laws\\[0\\].c"),
    ('[[laws]]\nname = "a"\nset = "controller.c=1"\n', "laws\\[0\\].set"),
])
def test_a_bad_laws_table_is_refused_naming_the_key(tmp_path: Path, laws: str,
                                                    match: str) -> None:
    res = suscosim("duty", str(_duty(tmp_path, laws)), "--out", str(tmp_path / "o"))
    assert res.returncode == 2, res.stdout + res.stderr
    assert re.search(match, res.stderr), res.stderr
    assert res.stderr.startswith("suscosim: error: duty: ")


def test_laws_with_a_finished_run_event_are_refused(tmp_path: Path) -> None:
    run = tmp_path / "run"
    run.mkdir()
    duty = _duty(tmp_path, "", f"""
[[events]]
name = "done"
run = "{run}"
repeats = 1
[[laws]]
name = "passive"
""")
    res = suscosim("duty", str(duty), "--out", str(tmp_path / "o"))
    assert res.returncode == 2 and "events[0].run" in res.stderr, res.stderr
