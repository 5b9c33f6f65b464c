"""python -m bench ch5-sine-bounds: the closed-form 2-DOF amplitudes against the time-domain sine
study, and the bound that puts Fig 5.13(c)'s 5 Hz force out of reach of the scaled MR damper."""

import numpy as np
import pytest

from bench import thesis_ch5 as sb
from bench.thesis_ch5 import sine_response, steady
from nodes.controller import mr_damper as mr


def test_closed_form_matches_time_domain_passive():
    freqs = [1.5, 5.0]
    r = sine_response({"law": "passive", "c": 1500.0}, freqs)
    for i, f in enumerate(freqs):
        s = steady(r, freqs, i)
        v, a = sb.linear_amplitudes(f, 1500.0)
        assert np.abs(s["v_rel"]).max() == pytest.approx(v, rel=0.02)
        assert np.abs(s["a_w"]).max() == pytest.approx(a, rel=0.02)


def test_scaled_mr_force_cannot_reach_fig_5_13c():
    p = mr.MRParams()
    vmax = max(sb.linear_amplitudes(5.0, c)[0] for c in np.linspace(0.0, 6000.0, 61))
    fy, cp = float(mr.yield_force(0.6, p)), float(mr.c_post(0.6, p))
    assert 0.628 * (fy + cp * 0.628 * vmax) < 0.85 * 2000.0   # the panel's lower end - 15 %
    assert 1.0 * (fy + cp * 1.0 * vmax) > 2000.0              # unscaled: inside the panel
