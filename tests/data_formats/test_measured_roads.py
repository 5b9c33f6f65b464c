"""#20 measured roads: OpenCRG surfaces (wheel tracks cut at the vehicle's track width) and
MDF 4 profiles; a malformed file is an error naming the file (exit 2 from the command)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cosim.errors import InputFileError, ScenarioError
from nodes.tyre_road.config import build_road
from nodes.tyre_road.measured import VEHICLE_TRACK_M

from ..conftest import CH3_STEP
from .conftest import cli

U = np.round(np.arange(0.0, 20.0 + 1e-9, 0.05), 10)
V = np.round(np.arange(-1.0, 1.0 + 1e-9, 0.05), 10)


def surface(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Long waves (2 m, 2 mm) plus a cross slope of 1 % (left up) plus a 30 mm bump at
    u = 8..8.5 m on the left half only."""
    z = 0.002 * np.sin(2 * np.pi * u[:, None] / 2.0) + 0.01 * v[None, :]
    bump = ((u >= 8.0) & (u <= 8.5))[:, None] & (v > 0.2)[None, :]
    return z + 0.03 * bump


@pytest.fixture(scope="module", params=["LDFI", "KDBI"])
def crg_file(request, tmp_path_factory) -> Path:
    """A tiny OpenCRG file (20 m x 2 m, 5 cm grid) written by pyopencrg, text or binary."""
    import pyopencrg

    path = tmp_path_factory.mktemp("crg") / f"tiny_{request.param}.crg"
    pyopencrg.CrgRoad(surface(U, V), u_inc=0.05, v=V).save(path, fmt=request.param)
    return path


def test_opencrg_tracks_cut_at_the_track_width(crg_file: Path) -> None:
    road = build_road({"type": "opencrg", "path": str(crg_file), "speed_kmh": 36.0,
                       "track_width": 1.0, "zero_start": False})
    assert road.length == pytest.approx(20.0) and road.speed == pytest.approx(10.0)
    s = U[:-1]
    left, right = road.height(s, 0), road.height(s, 1)
    np.testing.assert_allclose(left, surface(s, np.array([0.5]))[:, 0], atol=1e-12)
    np.testing.assert_allclose(right, surface(s, np.array([-0.5]))[:, 0], atol=1e-12)
    assert left[(s > 8.1) & (s < 8.4)].min() > 0.03 and np.abs(right).max() < 0.0075
    # default: the vehicle's track (v = +-0.7055 m, between grid lines: linear in v, exact)
    road = build_road({"type": "opencrg", "path": str(crg_file), "speed_kmh": 36.0})
    h = VEHICLE_TRACK_M / 2
    z0 = 0.01 * h  # the starting height, removed (zero_start)
    np.testing.assert_allclose(road.height(np.array([0.5, 12.0]), 0),
                               [0.002 * np.sin(np.pi * 0.5) + 0.01 * h - z0, 0.0], atol=1e-12)
    np.testing.assert_allclose(road.height(np.array([12.0]), 1), [0.0], atol=1e-12)


def test_opencrg_bad_files_and_keys_name_the_problem(crg_file: Path, tmp_path: Path) -> None:
    with pytest.raises(InputFileError, match="outside the road's width"):
        build_road({"type": "opencrg", "path": str(crg_file), "speed_kmh": 36.0,
                    "track_width": 2.5})
    with pytest.raises(InputFileError, match="longer than the road"):
        build_road({"type": "opencrg", "path": str(crg_file), "speed_kmh": 36.0,
                    "length_m": 50.0})
    with pytest.raises(ScenarioError, match="road.reference"):
        build_road({"type": "opencrg", "path": str(crg_file), "speed_kmh": 36.0,
                    "reference": "absolute"})
    bad = tmp_path / "bad.crg"
    bad.write_text("$CT\nnot a road\n$ROAD_CRG\nreference_line_increment = oops\n$$$$\n")
    with pytest.raises(InputFileError, match="bad.crg"):
        build_road({"type": "opencrg", "path": str(bad), "speed_kmh": 36.0})
    torn = tmp_path / "torn.crg"
    torn.write_bytes(crg_file.read_bytes()[: len(crg_file.read_bytes()) // 2])
    with pytest.raises(InputFileError, match="torn.crg"):
        build_road({"type": "opencrg", "path": str(torn), "speed_kmh": 36.0})


def _mdf(path: Path, t: np.ndarray, sigs: dict[str, tuple[np.ndarray, str]]) -> Path:
    from asammdf import MDF, Signal

    mdf = MDF(version="4.10")
    mdf.append([Signal(x, t, name=n, unit=u) for n, (x, u) in sigs.items()])
    mdf.save(str(path), overwrite=True)
    mdf.close()
    return path


def test_mdf4_profile_by_distance_channel_and_by_recorded_speed(tmp_path: Path) -> None:
    t = np.arange(0, 2.0, 0.01)
    x = 5.0 + 10.0 * t  # recorded at 36 km/h, from 5 m on
    zl, zr = 0.004 * np.sin(3 * x), 0.002 * np.cos(2 * x)
    path = _mdf(tmp_path / "profile.mf4", t, {"s": (x, "m"), "zl": (zl * 1e3, "mm"),
                                              "zr": (zr, "m")})
    road = build_road({"type": "mdf4", "path": str(path), "left": "zl", "right": "zr",
                       "distance": "s", "speed_kmh": 50.0, "zero_start": False})
    assert road.length == pytest.approx(x[-1] - x[0])
    np.testing.assert_allclose(road.height(x - 5.0, 0), zl, atol=1e-15)
    np.testing.assert_allclose(road.height(x - 5.0, 1), zr, atol=1e-15)
    road = build_road({"type": "mdf4", "path": str(path), "left": "zl",
                       "recorded_speed_kmh": 36.0, "speed_kmh": 50.0})
    np.testing.assert_allclose(road.height(10.0 * t, 1), zl - zl[0], atol=1e-12)
    for cfg, msg in (({"left": "nope", "distance": "s"}, "no channel 'nope'"),
                     ({"left": "zl"}, "distance"),
                     ({"left": "s", "right": "zl", "distance": "zl"}, "increase strictly")):
        with pytest.raises((InputFileError, ScenarioError), match=msg):
            build_road({"type": "mdf4", "path": str(path), "speed_kmh": 50.0, **cfg})
    bad = tmp_path / "bad.mf4"
    bad.write_bytes(b"MDF     4.10    " + b"\0" * 50)
    with pytest.raises(InputFileError, match="bad.mf4"):
        build_road({"type": "mdf4", "path": str(bad), "left": "zl", "distance": "s",
                    "speed_kmh": 50.0})


def test_a_run_on_an_opencrg_road_and_a_malformed_one_exits_2(crg_file: Path,
                                                              tmp_path: Path, capsys) -> None:
    road = f'road={{ type = "opencrg", path = "{crg_file}", speed_kmh = 36.0 }}'
    out = tmp_path / "run"
    rc, o, e = cli(capsys, "run", str(CH3_STEP), "--mode", "monolithic", "--quiet", "--out",
                   str(out), "--set", road, "--set", "run.t_end=1.0")
    assert rc == 0, o + e
    summary = json.loads((out / "summary.json").read_text())
    z_g = summary["channels"]["tyre_road/force/z_g"]
    # the quarter car's wheel is on the right track: waves and cross slope, no bump
    assert 0.0015 < z_g["max"] < 0.0025 and z_g["min"] > -0.0025
    bad = tmp_path / "bad.crg"
    bad.write_text("garbage\n")
    rc, o, e = cli(capsys, "run", str(CH3_STEP), "--mode", "monolithic", "--quiet", "--out",
                   str(tmp_path / "r2"), "--set",
                   f'road={{ type = "opencrg", path = "{bad}", speed_kmh = 36.0 }}')
    assert rc == 2 and str(bad) in e, o + e
