"""Issue #27 item 2: the MR damper and the laws against the numbers the thesis prints for
Sec 5.5.1 (tests/controller/data/thesis_ch5_sine.csv: Table 5.1, the text's 3800 / 6000 N s/m,
axis ranges of Figs 5.11-5.17). The full table: python -m bench ch5-sine-study."""

import csv
from pathlib import Path

import numpy as np
import pytest

from bench.thesis_ch5 import THESIS_LAWS, sine_response
from nodes.controller import mr_damper as mr

ROWS = {r["id"]: r for r in csv.DictReader(
    (Path(__file__).parent / "data" / "thesis_ch5_sine.csv").open())}


def test_table_51_values_are_the_model_s():
    p = mr.MRParams()
    assert float(mr.c_post(0.0, p)) == pytest.approx(float(ROWS["T51_cpost0"]["lo"]), rel=1e-4)
    assert float(mr.c_post(0.6, p)) == pytest.approx(float(ROWS["T51_cpost06"]["lo"]), rel=1e-4)
    assert float(mr.yield_force(0.0, p)) == pytest.approx(float(ROWS["T51_fy0"]["lo"]), rel=1e-3)
    assert float(mr.yield_force(0.6, p)) == pytest.approx(float(ROWS["T51_fy06"]["lo"]), rel=1e-3)
    # the text's hard rate (6000) is the 0.6 A post-yield slope within 15 %; its soft rate
    # (3800) is NOT Table 5.1's 0 A slope (3203, -15.7 %): the thesis is inconsistent there
    assert float(mr.c_post(0.6, p)) == pytest.approx(6000.0, rel=0.15)
    assert float(mr.c_post(0.0, p)) / 3800.0 - 1.0 == pytest.approx(-0.157, abs=0.002)


def test_fig_511d_10_hz_peak_force_in_the_axis_range():
    """Fig 5.11(d), 10 Hz, 10 mm: max |F_d| of TSS1/TSS2/TSS3 over the plotted 0-0.3 s lies
    in (2000, 3000] N (axis ticks; within 15 %)."""
    row = ROWS["F511d"]
    lo, hi = float(row["lo"]), float(row["hi"])
    peak = max(float(np.abs(sine_response(THESIS_LAWS[law], [10.0], t_end=0.3)["F_d"]).max())
               for law in ("tss1", "tss3"))
    assert 0.85 * lo <= peak <= 1.15 * hi
    # TSS3's current is exactly the two levels
    r = sine_response(THESIS_LAWS["tss3"], [10.0], t_end=0.3)
    assert set(np.unique(r["I"])) <= {0.0, 0.6}
