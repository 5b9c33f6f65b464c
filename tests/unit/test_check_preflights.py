"""#46 item 7: `suscosim check` refuses what the run would die on: a NaN in a .tir, a corner
hardpoint of 1e308 m, an MDF road 1e308 m high, a duty event of 1e308 repeats (each passed
check and the preflight before, then killed the run at step 0-50 or printed "inf km")."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cosim.errors import InputFileError
from tests.conftest import ROOT, suscosim

SCENARIO = ROOT / "scenarios" / "ch4_qvm_realistic_pave.toml"


def _check(*sets: str) -> str:
    res = suscosim("check", str(SCENARIO), *[a for s in sets for a in ("--set", s)],
                   timeout=60)
    assert res.returncode == 2, res.stdout + res.stderr
    return res.stderr.strip().splitlines()[-1]


def test_a_tir_with_a_nan_coefficient_is_refused_by_check(tmp_path: Path) -> None:
    text = (ROOT / "nodes" / "tyre_road" / "tyres" / "mpv_215_65r16.tir").read_text()
    assert "\nMASS                     = 11.0" in text
    tir = tmp_path / "nan.tir"
    tir.write_text(text.replace("\nMASS                     = 11.0",
                                "\nMASS                     = nan"))
    last = _check('tyre.model="magic_formula"', f'tyre.tir="{tir}"')
    assert "nan.tir" in last and "MASS" in last and "not a finite number" in last, last


def test_a_corner_hardpoint_of_1e308_m_is_refused_by_check_and_corner_check(
        tmp_path: Path) -> None:
    text = (ROOT / "cosim" / "corners" / "mpv_front.toml").read_text()
    assert "lower_ball_joint = [0.025, -0.06, -0.13]" in text
    corner = tmp_path / "huge.toml"
    corner.write_text(text.replace("lower_ball_joint = [0.025, -0.06, -0.13]",
                                   "lower_ball_joint = [0.025, -0.06, 1e308]"))
    last = _check(f'vehicle.corner="{corner}"')
    assert "huge.toml" in last and "lower_ball_joint" in last and "within" in last, last
    res = suscosim("corner", "check", str(corner), timeout=60)
    assert res.returncode == 2 and "lower_ball_joint" in res.stderr, res.stdout + res.stderr


def test_an_mdf_road_1e308_m_high_is_refused(tmp_path: Path) -> None:
    from nodes.tyre_road.config import build_road
    from tests.data_formats.test_measured_roads import _mdf

    t = np.arange(0, 2.0, 0.01)
    z = np.zeros_like(t)
    z[50] = 1e308
    path = _mdf(tmp_path / "high.mf4", t, {"s": (10.0 * t, "m"), "z": (z, "m")})
    with pytest.raises(InputFileError, match="'z': height 1e.308 m"):
        build_road({"type": "mdf4", "path": str(path), "left": "z", "distance": "s",
                    "speed_kmh": 36.0})


def test_a_duty_event_of_1e308_repeats_is_refused(tmp_path: Path) -> None:
    duty = tmp_path / "duty.toml"
    duty.write_text(f'[duty]\nname = "d"\n\n[[events]]\nname = "e"\n'
                    f'scenario = "{SCENARIO}"\nrepeats = 1e308\n')
    res = suscosim("duty", str(duty), "--out", str(tmp_path / "out"), timeout=60)
    assert res.returncode == 2, res.stdout + res.stderr
    assert "events[0].repeats" in res.stderr and "at most 1e+09" in res.stderr, res.stderr
