"""A road CSV whose heights are not a road is refused naming the file and the sample
(#30 item 14: a 50 m or 1e300 m bump ran 'ok', body at 10.9 m, F_t 1.9e305 N)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cosim.errors import InputFileError
from nodes.tyre_road.measured import MAX_STEP_M, measured_road, read_profile_csv


def _write(tmp_path: Path, z: np.ndarray) -> Path:
    p = tmp_path / "road.csv"
    x = np.arange(len(z)) * 0.05
    p.write_text("".join(f"{float(a)!r},{float(b)!r}\n" for a, b in zip(x, z, strict=True)))
    return p


@pytest.mark.parametrize("height", [50.0, 1e300])
def test_a_bump_that_is_no_road_is_refused(tmp_path: Path, height: float) -> None:
    z = np.zeros(400)
    z[100:300] = height * np.sin(np.linspace(0, np.pi, 200))  # a smooth hill of that height
    with pytest.raises(InputFileError, match=r"road\.csv.*column 2.*not a road profile"):
        read_profile_csv(_write(tmp_path, z))


def test_a_jump_between_samples_is_refused_a_kerb_is_not(tmp_path: Path) -> None:
    z = np.zeros(50)
    z[20:] = 0.15  # a kerb
    x, zl, _ = read_profile_csv(_write(tmp_path, z))
    assert zl.max() == pytest.approx(0.15)
    z[30:] = 0.15 + MAX_STEP_M + 0.01
    with pytest.raises(InputFileError, match="between data rows 30 and 31"):
        read_profile_csv(_write(tmp_path, z))


def test_a_measured_pave_profile_passes(tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    z = 0.3 + np.cumsum(rng.normal(0, 0.002, 2000))  # not detrended, not zero at the start
    road = measured_road("csv", _write(tmp_path, z), speed=9.44)
    assert road.length == pytest.approx(1999 * 0.05)
