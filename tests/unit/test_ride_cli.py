"""``suscosim ride`` on tiny synthetic run folders (tables written with the recorder's export)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cosim.table import export
from orchestrator import ride
from orchestrator.cli import main as cli_main


def _run_dir(folder: Path, amplitude: float) -> Path:
    """A 4 s run at 1 kHz with a 1.5 Hz body acceleration of the given amplitude [m/s²]."""
    t = np.arange(0, 4001) * 1e-3
    a_b = amplitude * np.sin(2 * np.pi * 1.5 * t)
    table = {
        "t": t,
        "plant/response/a_b": a_b,
        "plant/response/a_w": 10 * amplitude * np.sin(2 * np.pi * 11.0 * t),
        "plant/state/z_b": 0.01 * amplitude * np.sin(2 * np.pi * 1.5 * t),
        "plant/state/z_w": 0.002 * np.sin(2 * np.pi * 11.0 * t),
        "tyre_road/force/F_t": 5000.0 + 300 * amplitude * np.sin(2 * np.pi * 11.0 * t),
        "controller/force/F_d": 100 * amplitude * np.cos(2 * np.pi * 1.5 * t),
    }
    folder.mkdir(parents=True)
    export(table, folder)
    return folder


def test_table_with_change_against_the_first_run(tmp_path: Path, capsys) -> None:
    base = _run_dir(tmp_path / "passive", 1.0)
    better = _run_dir(tmp_path / "tss1", 0.8)
    assert ride.main([str(base), str(better)]) == 0
    out = capsys.readouterr().out
    header, _, *rows = out.splitlines()
    assert header.split() == ["metric", "passive", "tss1", "%"]
    assert rows[0].startswith("a_b RMS 0-20 Hz [m/s2]")  # the headline: the thesis's metric
    row = rows[0].split()
    assert float(row[5]) == pytest.approx(1 / np.sqrt(2), rel=1e-3)
    assert float(row[6]) == pytest.approx(0.8 / np.sqrt(2), rel=1e-3)
    assert float(row[7]) == pytest.approx(20.0, abs=0.05)
    names = [r.split(" [")[0] for r in rows]
    for metric in ("a_b RMS 0-16 Hz", "a_b RMS full band", "a_b Wk RMS", "jerk_b RMS", "SWS",
                   "DTL RMS"):
        assert metric in names


def test_baseline_and_band_options(tmp_path: Path, capsys) -> None:
    a = _run_dir(tmp_path / "a", 1.0)
    b = _run_dir(tmp_path / "b", 0.5)
    assert ride.main([str(a), str(b), "--baseline", "b", "--band", "1", "2"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0].split() == ["metric", "b", "a", "%"]
    row = next(r for r in out.splitlines() if r.startswith("a_b RMS 1-2 Hz")).split()
    assert float(row[-1]) == pytest.approx(-100.0, abs=0.5)  # a has twice b's 1.5 Hz RMS


def test_through_the_suscosim_cli(tmp_path: Path, capsys) -> None:
    a = _run_dir(tmp_path / "a", 1.0)
    assert cli_main(["ride", str(a)]) == 0
    assert "a_b RMS 0-20 Hz [m/s2]" in capsys.readouterr().out


def test_json_has_every_metric_of_every_run(tmp_path: Path, capsys) -> None:
    base = _run_dir(tmp_path / "passive", 1.0)
    better = _run_dir(tmp_path / "tss1", 0.8)
    assert cli_main(["ride", str(base), str(better), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["baseline"] == "passive"
    assert [(r["name"], r["path"]) for r in out["runs"]] == [
        ("passive", str(base)), ("tss1", str(better))]
    p, b = (r["metrics"] for r in out["runs"])
    assert set(p) == set(b) >= {"a_b_rms", "a_b_rms_0_16", "a_b_rms_full", "a_b_wk_rms",
                                "jerk_b_rms", "a_w_rms", "sws", "defl_rms", "dtl_rms", "f_d_rms"}
    assert p["a_b_rms"] == pytest.approx(1 / np.sqrt(2), rel=1e-3)
    assert b["a_b_rms"] == pytest.approx(0.8 / np.sqrt(2), rel=1e-3)
    assert b["dtl_rms"] == pytest.approx(0.8 * 300 / np.sqrt(2), rel=1e-3)
    assert out["runs"][1]["change_pct"]["a_b_rms"] == pytest.approx(20.0, abs=0.05)
    assert out["units"]["a_b_rms"] == "m/s2" and out["units"]["sws"] == "mm"


def test_json_change_against_a_zero_baseline_is_null(tmp_path: Path, capsys) -> None:
    zero = _run_dir(tmp_path / "still", 0.0)
    moving = _run_dir(tmp_path / "moving", 1.0)
    assert ride.main([str(zero), str(moving), "--json"]) == 0
    text = capsys.readouterr().out
    assert "NaN" not in text
    assert json.loads(text)["runs"][1]["change_pct"]["a_b_rms"] is None


@pytest.mark.parametrize("json_flag", [[], ["--json"]], ids=["text", "json"])
@pytest.mark.parametrize("case", ["missing_dir", "missing_table", "bad_baseline", "bad_band"])
def test_errors_print_one_line_and_return_2(tmp_path: Path, capsys, case: str,
                                            json_flag: list[str]) -> None:
    a = _run_dir(tmp_path / "a", 1.0)
    args = {
        "missing_dir": [str(a), str(tmp_path / "nope")],
        "missing_table": [str(a), str((tmp_path / "empty").mkdir() or tmp_path / "empty")],
        "bad_baseline": [str(a), "--baseline", "zzz"],
        "bad_band": [str(a), "--band", "5", "1"],
    }[case] + json_flag
    assert ride.main(args) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("suscosim ride:")


def test_same_folder_names_are_told_apart(tmp_path: Path, capsys) -> None:
    a = _run_dir(tmp_path / "x" / "run", 1.0)
    b = _run_dir(tmp_path / "y" / "run", 0.9)
    assert ride.main([str(a), str(b)]) == 0
    assert capsys.readouterr().out.splitlines()[0].split() == ["metric", "x/run", "y/run", "%"]
