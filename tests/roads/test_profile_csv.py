"""Measured profile from CSV: parsing, tracks, and clear errors for malformed files."""

import numpy as np
import pytest

from cosim.errors import InputFileError
from nodes.tyre_road.config import build_road


def _write(tmp_path, text):
    p = tmp_path / "profile.csv"
    p.write_text(text)
    return str(p)


def test_two_and_three_columns(tmp_path):
    path = _write(tmp_path, "# LTC-like\ndistance,left,right\n"
                            "0,0.01,0.02\n1,0.03,0.0\n2,0.01,0.04\n")
    road = build_road({"type": "csv", "speed_kmh": 36, "path": path})
    assert road.length == 2.0 and road.duration_s == pytest.approx(0.2)
    # zero_start shifts each track to start at 0
    assert np.allclose(road.height(np.array([0.0, 0.5, 1.0]), 0), [0.0, 0.01, 0.02])
    assert np.allclose(road.height(np.array([1.0, 2.0]), 1), [-0.02, 0.02])
    path2 = _write(tmp_path, "0,0\n1,0.01\n")
    road2 = build_road({"type": "csv", "speed_kmh": 36, "path": path2, "zero_start": False})
    assert np.allclose(road2.height(np.array([1.0]), 1), 0.01)


@pytest.mark.parametrize("text,line,words", [
    ("0,0\n1,abc\n", 2, "not a finite number"),
    ("0,0\n1,0.1,0.2\n", 2, "columns"),
    ("0,0\n0,0.1\n", 2, "increase"),
    ("0,0,0,0\n", 1, "2 or 3"),
    ("0,0\n", None, "at least 2"),
    ("", None, "at least 2"),
    ("0,0\n1,nan\n", 2, "finite"),
])
def test_malformed_files(tmp_path, text, line, words):
    path = _write(tmp_path, text)
    with pytest.raises(InputFileError) as e:
        build_road({"type": "csv", "speed_kmh": 36, "path": path})
    assert e.value.line == line
    assert words in e.value.problem
    assert e.value.path == path


def test_missing_file(tmp_path):
    with pytest.raises(InputFileError, match="not found"):
        build_road({"type": "csv", "speed_kmh": 36, "path": str(tmp_path / "nope.csv")})
