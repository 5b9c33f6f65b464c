"""PC vs FFP on the Ch. 3 step: PC peak higher, FFP rises in n stages and lags."""

import numpy as np
import pytest

from nodes.tyre_road.tyre_step_study import K_T, M_B, M_W, step_response
from nodes.tyre_road.tyres import FixedFootprint, PointContact


def test_pc_peak_higher_and_ffp_staircase():
    v = 47 / 3.6
    kw = {"t_end": 0.65, "dt": 1e-4}
    pc = step_response(PointContact(K_T), v, **kw)
    ffp = step_response(FixedFootprint(4, 0.2, K_T), v, **kw)
    W = (M_B + M_W) * 9.81
    assert pc["F_t"].max() == pytest.approx(W + K_T * 0.02, rel=1e-3)  # 7400 N, Sec. 3 check
    ratio = pc["F_t"].max() / ffp["F_t"].max() - 1
    assert 0.05 < ratio < 0.12  # thesis: about 7 %
    assert np.argmax(ffp["F_t"]) > np.argmax(pc["F_t"])  # FFP peak lags
    # staircase: four jumps of k_t/4 * 20 mm = 960 N, one per spring reaching the step
    jumps = np.diff(ffp["F_t"])
    big = jumps[jumps > 300]
    assert len(big) == 4
    assert np.allclose(big, K_T / 4 * 0.02, rtol=0.1)
