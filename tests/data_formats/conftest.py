"""Finished realistic-corner runs shared by the data-format and duty-cycle tests (short:
0.6 s of the Chapter 6 scenario, monolithic, batch fatigue of the coarse arm: the tests
compare lives of the same part, not the CAD arm's own numbers)."""

from __future__ import annotations

from pathlib import Path

import pytest

from ..conftest import COARSE_ARM, ROOT, suscosim

REALISTIC = ROOT / "scenarios" / "thesis" / "ch6_realistic_qvm.toml"
BUMP_POTHOLE = ('road={ type = "events", speed_kmh = 34.0, length_m = 15.0, events = ['
                '{ type = "bump", height = 0.05, length = 1.0, x_start = 3.0 }, '
                '{ type = "pothole", depth = 0.04, length = 0.6, x_start = 10.0 }] }')


def cli(capsys, *args: str) -> tuple[int, str, str]:
    """``suscosim ARGS`` in this process (the CLI's own code; no interpreter start-up)."""
    from orchestrator.cli import main

    capsys.readouterr()
    rc = main(list(args))
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


def finished_run(out: Path, *sets: str, t_end: float = 0.6) -> Path:
    """Run the Chapter 6 realistic scenario (monolithic) into ``out`` and its batch fatigue."""
    args = ["run", str(REALISTIC), "--out", str(out), "--quiet", "--mode", "monolithic",
            "--set", f"run.t_end={t_end}", "--set", "fatigue.live=false",
            "--set", f'fatigue.influence="{COARSE_ARM}"']
    for s in sets:
        args += ["--set", s]
    res = suscosim(*args, timeout=240)
    assert res.returncode == 0, res.stdout + res.stderr
    from nodes.fatigue.run_dir import fatigue_run_dir

    fatigue_run_dir(out)  # what `suscosim fatigue RUN_DIR` does, in this process
    return out


@pytest.fixture(scope="session")
def pave_run(tmp_path_factory) -> Path:
    """0.6 s of the pave (1201 rows), 100 m pass length."""
    return finished_run(tmp_path_factory.mktemp("runs") / "pave")


@pytest.fixture(scope="session")
def bump_run(tmp_path_factory) -> Path:
    """The bump + pothole road (15 m pass length), 0.6 s: over the bump (at 3 m)."""
    return finished_run(tmp_path_factory.mktemp("runs") / "bump", BUMP_POTHOLE)
