"""Synthetic pavé: stone statistics, joints, crowns, seeds, tracks, scenario keys."""

import numpy as np
import pytest
from scipy.signal import welch

from cosim.errors import ScenarioError
from nodes.tyre_road.cobblestone import (
    DX,
    PaveParameters,
    pave_profile,
    stone_heights,
    stone_layout,
)
from nodes.tyre_road.config import build_road

BASE = {"type": "pave", "speed_kmh": 34.0, "length_m": 100.0, "seed": 5}


def _flat(**kw) -> PaveParameters:
    """Stones only: long waves made negligible (G tiny), so the stone geometry is exact."""
    return PaveParameters(**{"G": 1e-30, **kw})


def test_stone_length_statistics():
    p = _flat(stone_length=0.15, stone_length_std=0.03)
    _, lengths, heights = stone_layout(2000.0, np.random.default_rng(1), p)
    assert lengths.size > 10000
    assert lengths.mean() == pytest.approx(0.15, rel=0.01)
    assert lengths.std() == pytest.approx(0.03, rel=0.05)
    assert lengths.min() > 0.0
    assert heights.std() == pytest.approx(p.stone_height_std, rel=0.05)


def test_layout_covers_the_road_and_joints_have_the_given_width():
    p = _flat(joint_width=0.012)
    starts, lengths, _ = stone_layout(50.0, np.random.default_rng(2), p)
    assert starts[0] <= 0.0 < starts[0] + lengths[0] + p.joint_width
    assert starts[-1] > 50.0
    np.testing.assert_allclose(starts[1:] - (starts[:-1] + lengths[:-1]), 0.012, atol=1e-12)


def test_joint_depth_below_the_chord_and_crown_above_the_edges():
    p = _flat(joint_depth=0.007, crown=0.003, joint_width=0.015)
    starts, lengths, heights = stone_layout(20.0, np.random.default_rng(3), p)
    for i in range(1, 40):
        b = starts[i] + lengths[i]  # end of stone i = start of its joint
        mid_joint = stone_heights(np.array([b + 0.0075]), starts, lengths, heights, p)[0]
        chord = 0.5 * (heights[i] + heights[i + 1])
        assert mid_joint == pytest.approx(chord - 0.007, abs=1e-12)
        mid_stone = stone_heights(np.array([starts[i] + 0.5 * lengths[i]]),
                                  starts, lengths, heights, p)[0]
        assert mid_stone == pytest.approx(heights[i] + 0.003, abs=1e-12)
        edges = stone_heights(np.array([starts[i], b, b + 0.015]), starts, lengths,
                              heights, p)
        np.testing.assert_allclose(edges, [heights[i], heights[i], heights[i + 1]],
                                   atol=1e-12)  # continuous: no vertical wall


def test_profile_joint_count_and_depth_on_the_sampled_track():
    """On the tabulated track (long waves off, no height scatter, no crown) the dips are the
    joints: one per stone pitch, each d deep."""
    p = _flat(stone_height_std=0.0, crown=0.0, joint_depth=0.006)
    x, zl, _, lay = pave_profile(30.0, 4, p)
    z = zl - zl.max()  # stone tops at 0
    in_joint = z < -1e-9
    n_joints = np.count_nonzero(np.diff(in_joint.astype(int)) == 1)
    starts = lay["left"][0]
    expected = np.count_nonzero((starts > x[0]) & (starts < x[-1]))
    assert abs(n_joints - expected) <= 1
    assert z.min() == pytest.approx(-0.006, abs=1e-4)
    assert DX <= p.joint_width / 7


def test_reproducible_by_seed_and_tracks_differ():
    s = np.arange(0.0, 100.0, 0.003)
    a = build_road(BASE)
    b = build_road(BASE)
    c = build_road({**BASE, "seed": 6})
    for track in (0, 1):
        assert np.array_equal(a.height(s, track), b.height(s, track))
        assert not np.allclose(a.height(s, track), c.height(s, track))
    assert a.height(np.array([0.0]), 0)[0] == 0.0 == a.height(np.array([0.0]), 1)[0]
    # own stones per track even with identical long waves
    d = build_road({**BASE, "correlation": "identical"})
    diff = d.height(s, 0) - d.height(s, 1)
    assert np.std(diff) > 0.003


def test_low_frequency_psd_of_the_stone_heights():
    """In the ride band the stones act as a piecewise-constant random process: one-sided PSD
    about 2 s_h^2 E[P^2] / E[P] at n << 1 / P (a renewal process of iid levels held over the
    pitch P = L + w; measured 0.93-0.97 of it, the ramps across the joints mixing
    neighbours)."""
    p = _flat(stone_height_std=0.005, crown=0.0, joint_depth=0.0)
    x, zl, _, _ = pave_profile(3000.0, 7, p)
    n, S = welch(zl, fs=1.0 / DX, nperseg=2 ** 16)
    band = (n > 0.2) & (n < 1.0)
    L, sL, w = p.stone_length, p.stone_length_std, p.joint_width
    expected = 2.0 * p.stone_height_std ** 2 * ((L + w) ** 2 + sL ** 2) / (L + w)
    assert S[band].mean() == pytest.approx(expected, rel=0.10)


@pytest.mark.parametrize("key,value", [
    ("stone_length", 0.0), ("stone_length_std", 0.2), ("joint_width", -0.01),
    ("joint_depth", -0.001), ("stone_height_std", "big"), ("crown", -1.0), ("G", 0.0),
    ("band", [1.0, 0.5]), ("correlation", "left"), ("seed", -3), ("length_m", None),
    ("stones", 3),
])
def test_bad_keys_name_the_key(key, value):
    cfg = dict(BASE)
    if value is None:
        del cfg[key]
    else:
        cfg[key] = value
    with pytest.raises(ScenarioError, match=rf"road\.{key}"):
        build_road(cfg)
