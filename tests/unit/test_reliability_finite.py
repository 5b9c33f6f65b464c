"""#15 item 2: non-finite physics refused (exit 2 naming the key), summary.json strict JSON."""

from __future__ import annotations

import json
import signal
from pathlib import Path

import pytest

from cosim import scenario as sc
from cosim.errors import ScenarioError
from orchestrator.cli import main as cli_main
from orchestrator.runner import write_summary

ROOT = Path(__file__).resolve().parents[2]
CH3 = ROOT / "scenarios" / "ch3_step_quarter_car.toml"


@pytest.mark.parametrize("assignment,key", [
    ("tyre.stiffness=inf", "tyre.stiffness"),
    ("vehicle.sprung_mass=inf", "vehicle.sprung_mass"),
    ("road.height=nan", "road.height"),
    ("controller.c=-inf", "controller.c"),
    ("run.h=nan", "run.h"),
    ("vehicle.unsprung_mass=-nan", "vehicle.unsprung_mass"),
    ("tyre.damping=inf", "tyre.damping"),
    ("road.extra=[0.0, 1.0, inf]", "road.extra[2]"),
    ("controller={law=\"passive\", c=nan}", "controller.c"),
])
def test_a_non_finite_number_anywhere_is_refused_naming_the_key(assignment, key) -> None:
    with pytest.raises(ScenarioError) as exc:
        sc.load(CH3, [assignment])
    assert exc.value.key == key and "finite" in str(exc.value)


def test_nan_in_the_scenario_file_itself(tmp_path: Path) -> None:
    text = CH3.read_text().replace("height = 0.02", "height = nan")
    assert "height = nan" in text
    (tmp_path / "s.toml").write_text(text)
    with pytest.raises(ScenarioError, match="road.height"):
        sc.load(tmp_path / "s.toml")


@pytest.mark.parametrize("assignment", ["tyre.stiffness=inf", "vehicle.sprung_mass=inf",
                                        "road.height=nan"])
def test_suscosim_run_exits_2_before_anything_starts(tmp_path: Path, capsys,
                                                     assignment: str) -> None:
    out = tmp_path / "run"
    before = signal.getsignal(signal.SIGTERM)  # `run` installs its own handler
    try:
        code = cli_main(["run", str(CH3), "--set", assignment, "--out", str(out),
                         "--mode", "monolithic", "--quiet"])
    finally:
        signal.signal(signal.SIGTERM, before)
    err = capsys.readouterr().err
    assert code == 2
    assert f"scenario key '{assignment.split('=')[0]}'" in err and "finite" in err
    assert "Traceback" not in err and not out.exists()


def _strict_loads(text: str) -> object:
    def refuse(name: str) -> None:
        raise ValueError(f"not JSON: {name}")
    return json.loads(text, parse_constant=refuse)


def test_summary_json_is_strict_json_and_says_what_was_nulled(tmp_path: Path, capsys) -> None:
    summary = {"status": "ok", "wall_s": 1.0,
               "channels": {"plant/state/z_b": {"peak": float("nan"), "rms": float("inf"),
                                                "max": 0.1}},
               "list": [1.0, float("-inf")]}
    write_summary(tmp_path, summary)
    back = _strict_loads((tmp_path / "summary.json").read_text())
    assert back["channels"]["plant/state/z_b"] == {"peak": None, "rms": None, "max": 0.1}
    assert back["list"] == [1.0, None]
    assert back["non_finite"] == ["channels.plant/state/z_b.peak",
                                  "channels.plant/state/z_b.rms", "list[1]"]
    assert "3 non-finite value(s) written as null" in capsys.readouterr().err


def test_a_finite_summary_is_written_unchanged(tmp_path: Path) -> None:
    summary = {"status": "ok", "rows": 3, "channels": {"a": {"peak": 1.5}}}
    write_summary(tmp_path, summary)
    assert _strict_loads((tmp_path / "summary.json").read_text()) == summary
    assert "non_finite" not in summary
