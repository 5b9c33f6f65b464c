"""Issue #30 items 7, 8 and 9: ``--set`` on a table, ``suscosim check``, ``--version``, the
grouped ``--help``, one error prefix, the progress bar's phases and ETA, units in the channel
printout."""

from __future__ import annotations

import argparse
import io
import tomllib
from importlib.metadata import version

import pytest

from cosim import scenario as sc
from orchestrator import cli
from orchestrator.cli_util import fail, parse_args
from orchestrator.progress import ProgressBar, format_eta
from orchestrator.runner import resolve
from tests.conftest import CH3_STEP, ROOT

TSS1 = ROOT / "scenarios" / "ch5_qvm_tss1_random.toml"


def run_cli(capsys, *argv: str) -> tuple[int, str, str]:
    code = cli.main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_set_one_key_of_a_table_says_how_to_replace_the_whole_table(capsys) -> None:
    code, _, err = run_cli(capsys, "check", str(CH3_STEP), "--set", 'controller.law="skyhook"')
    assert code == 2
    assert err.startswith("suscosim: error: scenario key 'controller.c'")
    assert "'c' comes from the scenario file" in err
    assert "--set 'controller={law=\"skyhook\", ...}'" in err


def test_a_whole_table_given_with_set_replaces_the_files_table(capsys) -> None:
    code, out, err = run_cli(capsys, "check", str(CH3_STEP), "--set", 'run.id="t-whole"',
                             "--set", 'controller={law="skyhook", c_sky=2500.0}')
    assert code == 0, err
    resolved = tomllib.loads(out)
    assert resolved["controller"] == {"law": "skyhook", "c_sky": 2500.0}  # c is gone


def test_a_typo_set_by_the_user_gets_no_whole_table_hint(capsys) -> None:
    code, _, err = run_cli(capsys, "check", str(CH3_STEP), "--set", "controller.cc=1.0")
    assert code == 2 and "controller.cc" in err and "did you mean 'c'" in err
    assert "give it whole" not in err


def test_switching_a_preset_law_to_an_fmu_names_the_leftover_preset(capsys) -> None:
    text = TSS1.read_text()
    assert 'preset' in text  # the scenario this is about
    code, _, err = run_cli(capsys, "check", str(TSS1), "--set", 'controller.law="fmu"',
                           "--set", 'controller.fmu="x.fmu"')
    assert code == 2 and "'controller.preset'" in err
    assert "--set 'controller={law=\"fmu\", fmu=\"x.fmu\", ...}'" in err


def test_check_prints_the_resolved_scenario_as_toml_equal_to_runs(capsys, tmp_path,
                                                                  monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(capsys, "check", str(CH3_STEP), "--set", 'run.id="t-check"',
                             "--set", "run.h=0.002", "--mode", "monolithic")
    assert code == 0, err
    first, body = out.split("\n", 1)
    assert "ok: 2000 steps of h = 0.002 s" in first
    expected = resolve(sc.load(CH3_STEP, ['run.id="t-check"', "run.h=0.002",
                                          'run.mode="monolithic"']))
    assert tomllib.loads(body) == expected
    assert list(tmp_path.iterdir()) == []  # nothing written, no run folder


def test_check_runs_the_preflight_of_run(capsys) -> None:
    """The model sections are checked by the node kinds' preflight, not by sc.load alone."""
    sc.load(CH3_STEP, ['tyre.model="no_such"'])  # the common check lets it through
    code, _, err = run_cli(capsys, "check", str(CH3_STEP), "--set", 'tyre.model="no_such"')
    assert code == 2 and "'tyre.model'" in err and "Traceback" not in err


def test_version_is_the_installed_packages(capsys) -> None:
    with pytest.raises(SystemExit) as ex:
        cli.main(["--version"])
    assert ex.value.code == 0
    assert capsys.readouterr().out.strip() == f"suscosim {version('suscosim')}"


def test_help_lists_every_command_once_everyday_apart_from_plumbing() -> None:
    text = cli.build_parser().format_help()
    every = text.split("everyday commands:")[1].split("results and model cards:")[0]
    plumbing = text.split("plumbing")[1]
    names = lambda block: [ln.split()[0] for ln in block.splitlines()  # noqa: E731
                           if ln.startswith("  ") and ln.split()]
    assert names(every) == ["run", "check", "sweep", "report", "fatigue", "duty", "scope",
                            "part", "corner"]
    assert {"node", "router", "cluster", "tap", "replay", "export-fmu"} <= set(names(plumbing))
    sub = next(a for a in cli.build_parser()._actions
               if isinstance(a, argparse._SubParsersAction))
    listed = [c[0] for _, cmds in cli.COMMANDS for c in cmds]
    assert sorted(listed) == sorted(sub.choices)  # each once, none left out


def test_error_lines_start_alike(capsys) -> None:
    assert fail("suscosim replay", "--wait -1: expected a time >= 0 s") == 2
    assert capsys.readouterr().err == "suscosim: error: replay: --wait -1: expected a time " \
                                      ">= 0 s\n"
    ap = argparse.ArgumentParser(prog="suscosim tap")
    ap.add_argument("--count", type=int)
    assert parse_args(ap, ["--count", "x"]) == 2
    assert "suscosim: error: tap: argument --count: invalid int" in capsys.readouterr().err
    code, _, err = run_cli(capsys, "check", str(ROOT / "no-such.toml"))
    assert code == 2 and err.startswith("suscosim: error: ")


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_bar_shows_the_start_up_phases_then_the_eta() -> None:
    stream = _Tty()
    bar = ProgressBar("r1", stream=stream, min_interval_s=0.0)
    bar(-1, 4000)  # the clock's start barrier
    assert [p for p, _ in bar.phases] == ["starting nodes", "handshake"]
    assert "r1 starting nodes" in stream.getvalue() and "r1 handshake" in stream.getvalue()
    # 1000 steps per second from the first step shown: 3000 left -> 3 s
    assert bar.line(0, 4000, now=100.0).endswith("ETA --:--")
    text = bar.line(1000, 4000, now=101.0)
    assert "1000 steps/s" in text and text.endswith("ETA 0:03")
    assert format_eta(3725) == "1:02:05" and format_eta(float("nan")) == "--:--"


def test_the_channel_printout_carries_si_units(capsys) -> None:
    cli._print_summary({"run_id": "r", "status": "ok", "mode": "m", "exchange": "e",
                        "coupling": "c", "h": 0.001, "n_steps": 1, "wall_s": 1.0,
                        "steps_per_s": 1.0,
                        "channels": {"tyre_road/force/F_t": {"peak": 1.0, "rms": 1.0},
                                     "plant/state/v_b": {"peak": 1.0, "rms": 1.0},
                                     "tyre_road/force/k_t": {"peak": 1.0, "rms": 1.0}}})
    rows = {ln.split()[0]: ln.split()[-1] for ln in capsys.readouterr().out.splitlines()
            if ln.split() and ln.split()[0].count("/") == 2}
    assert rows == {"tyre_road/force/F_t": "N", "plant/state/v_b": "m/s",
                    "tyre_road/force/k_t": "N/m"}


def test_the_rate_stops_at_the_last_step() -> None:
    bar = ProgressBar("r", stream=_Tty(), start_phase="")
    bar.line(0, 100, now=0.0)
    assert "100 steps/s" in bar.line(100, 100, now=1.0)
    assert "100 steps/s" in bar.line(100, 100, now=5.0)  # the recorder exporting: same rate
