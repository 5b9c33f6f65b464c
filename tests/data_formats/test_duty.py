"""#20 duty cycles: the schedule's damage is the sum of the events' damages times their
repeats, node by node; life in schedules and km; the dominant event; life at a probability of
survival from a log-normal S-N scatter (closed form)."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

from nodes.fatigue.lib.duty_cycle import (
    Z_90,
    Event,
    life_factor,
    log10_std_from_scatter_band,
    schedule_damage,
)

from ..conftest import COARSE_ARM, suscosim
from .conftest import BUMP_POTHOLE, REALISTIC, cli


def test_schedule_damage_sums_repeats_times_damage_per_node() -> None:
    a = Event("pave", np.array([1e-6, 4e-6, 0.0]), 100.0, 200)
    b = Event("pothole", np.array([5e-5, 1e-6, 2e-7]), 15.0, 50)
    r = schedule_damage([a, b])
    np.testing.assert_allclose(r.total, [200e-6 + 50 * 5e-5, 800e-6 + 50e-6, 1e-5])
    assert r.critical == 0 and r.dominant == 1  # 2.5e-3 from the potholes vs 2e-4
    assert r.distance_m == 200 * 100 + 50 * 15
    assert r.life_schedules == pytest.approx(1 / 2.7e-3)
    assert r.life_km == pytest.approx(20.75 / 2.7e-3)
    assert r.shares() == pytest.approx([2e-4 / 2.7e-3, 2.5e-3 / 2.7e-3])
    with pytest.raises(ValueError, match="nodes"):
        schedule_damage([a, Event("x", np.ones(2), 1.0, 1)])


def test_life_at_probability_closed_form() -> None:
    assert life_factor(0.5, 0.3) == 1.0  # the median curve
    # one standard deviation above the median: 10^-s
    assert life_factor(0.8413447460685429, 0.2) == pytest.approx(10 ** -0.2, rel=1e-9)
    # a scatter band T_N = N10/N90: at 90 % survival the life is N50 / sqrt(T_N)
    s = log10_std_from_scatter_band(3.0)
    assert s == pytest.approx(math.log10(3.0) / (2 * 1.2815515655446004))
    assert life_factor(0.9, s) == pytest.approx(1 / math.sqrt(3.0), rel=1e-12)
    assert life_factor(0.1, s) == pytest.approx(math.sqrt(3.0), rel=1e-12)
    assert Z_90 == pytest.approx(1.2815515655446004)
    for bad in (0.0, 1.0):
        with pytest.raises(ValueError):
            life_factor(bad, s)
    with pytest.raises(ValueError):
        log10_std_from_scatter_band(0.5)


def _damage(run: Path) -> dict[int, float]:
    with open(run / "fatigue" / "damage_per_node.csv", newline="") as fh:
        return {int(r["node_id"]): float(r["damage_per_pass"]) for r in csv.DictReader(fh)}


@pytest.mark.integration
def test_duty_of_chapter6_events_sums_their_damage(pave_run: Path, bump_run: Path,
                                                   tmp_path: Path) -> None:
    duty = tmp_path / "duty.toml"
    duty.write_text(f"""
[duty]
name = "pg"
scatter_band = 3.0
survival_probability = 0.9
[[events]]
name = "pave"
run = "{pave_run}"
repeats = 200
[[events]]
name = "bump_pothole"
run = "{bump_run}"
distance_km = 1.5
[[events]]
name = "pave_again"
scenario = "{REALISTIC}"
set = ["run.t_end=0.2", "fatigue.live=false", 'fatigue.influence="{COARSE_ARM}"']
repeats = 7
""")
    out = tmp_path / "out"
    res = suscosim("duty", str(duty), "--out", str(out), "--mode", "monolithic", timeout=240)
    assert res.returncode == 0, res.stdout + res.stderr
    got = json.loads((out / "duty.json").read_text())
    runs = [pave_run, bump_run, out / "runs" / "pave_again"]
    d = [_damage(r) for r in runs]
    repeats = [200.0, 1500.0 / 15.0, 7.0]
    assert [e["repeats"] for e in got["events"]] == pytest.approx(repeats)
    ids = sorted(d[0])
    expect = {i: sum(n * dd[i] for n, dd in zip(repeats, d, strict=True)) for i in ids}
    with open(out / "damage_per_node.csv", newline="") as fh:
        rows = {int(r["node_id"]): r for r in csv.DictReader(fh)}
    assert sorted(rows) == ids
    for i in ids:
        assert float(rows[i]["damage_per_schedule"]) == pytest.approx(expect[i], rel=1e-5,
                                                                       abs=1e-300)
    crit = max(ids, key=expect.get)
    assert got["critical_node_id"] == crit
    assert got["max_damage_per_schedule"] == pytest.approx(expect[crit], rel=1e-12)
    km = (200 * 100 + 1500 + 7 * 100) / 1000  # pass length: road.length_m
    assert got["schedule_distance_km"] == pytest.approx(km)
    assert got["life_schedules"] == pytest.approx(1 / expect[crit], rel=1e-12)
    assert got["life_km"] == pytest.approx(km / expect[crit], rel=1e-12)
    contrib = [n * dd[crit] for n, dd in zip(repeats, d, strict=True)]
    assert got["dominant_event"] == got["events"][int(np.argmax(contrib))]["name"]
    assert sum(e["share_at_critical"] for e in got["events"]) == pytest.approx(1.0)
    cert = got["certainty"]
    assert cert["life_km"] == pytest.approx(got["life_km"] / math.sqrt(3.0), rel=1e-12)
    assert "dominant event" in res.stdout and (out / "events.csv").is_file()
    # the report's duty page: every event, the critical node, the certainty, a map
    from orchestrator.report.cli import render
    from orchestrator.report.markup import fmt

    kind, html = render(out)
    assert kind == "duty"
    for e in got["events"]:
        assert f"<td>{e['name']}</td>" in html
    assert f"{crit} at (" in html and fmt(got["life_km"]) in html
    assert "Certainty of survival" in html and fmt(cert["life_km"]) in html
    assert html.count("data:image/png;base64,") == 2  # shares chart and damage map


def test_report_of_a_damaged_duty_folder_is_exit_2(tmp_path: Path, capsys) -> None:
    (tmp_path / "duty.json").write_text("{not json")
    rc, _, err = cli(capsys, "report", str(tmp_path))
    assert rc == 2 and "duty.json" in err
    (tmp_path / "duty.json").write_text('{"name": "x"}')
    rc, _, err = cli(capsys, "report", str(tmp_path))
    assert rc == 2 and "no 'events' list" in err


@pytest.mark.parametrize("body, key", [
    ("[[events]]\nname = 'a'\nrepeats = 1\n", "events[0].scenario"),
    ("[[events]]\nscenario = 'missing.toml'\nrepeats = 1\n", "missing.toml"),
    ("[duty]\nsurvival_probability = 0.9\n[[events]]\nrun = '.'\nrepeats = 1\n",
     "duty.log10_std"),
    ("[duty]\nscatter_band = 0.5\n[[events]]\nrun = '.'\nrepeats = 1\n", "duty.scatter_band"),
    ("[[events]]\nrun = '.'\nrepeats = -1\n", "events[0].repeats"),
    ("[[events]]\nrun = '.'\nrepeats = 1\ndistance_km = 2\n", "events[0].repeats"),
    ("[[events]]\nrun = '.'\nrepeat = 1\n", "did you mean 'repeats'"),
    ("[dutty]\n[[events]]\nrun = '.'\nrepeats = 1\n", "did you mean 'duty'"),
    (f"[[events]]\nscenario = '{Path(__file__).resolve().parents[2]}/scenarios/"
     "ch3_step_quarter_car.toml'\nrepeats = 1\n[[laws]]\nname = 'a'\nsett = []\n",
     "did you mean 'set'"),
    ("[duty\n", "not valid TOML"),
])
def test_bad_duty_file_exit_2_naming_the_key(tmp_path: Path, body: str, key: str,
                                             capsys) -> None:
    duty = tmp_path / "d.toml"
    duty.write_text(body)
    rc, out, err = cli(capsys, "duty", str(duty), "--out", str(tmp_path / "o"))
    assert rc == 2, out + err
    assert key in err and not (tmp_path / "o").exists()


def test_bad_duty_file_from_the_command_line(tmp_path: Path) -> None:
    duty = tmp_path / "d.toml"
    duty.write_text("[[events]]\nrun = 'nowhere'\nrepeats = 3\n")
    res = suscosim("duty", str(duty))
    assert res.returncode == 2, res.stdout + res.stderr
    assert "nowhere" in res.stderr and "run folder not found" in res.stderr
    assert "Traceback" not in res.stderr


def test_shipped_duty_file_is_valid() -> None:
    from orchestrator.duty import load_duty

    duty = load_duty(Path(__file__).resolve().parents[2] / "scenarios" / "duty" /
                     "ch6_proving_ground.toml")
    assert [e["name"] for e in duty["events"]] == ["pave", "bump_pothole", "b_road"]
    assert duty["log10_std"] == pytest.approx(math.log10(3) / (2 * Z_90))
    assert BUMP_POTHOLE.split("=", 1)[0] == "road"
