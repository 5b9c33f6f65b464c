"""A seeded synthetic pavé (Belgian block / cobblestone durability track) profile.

The thesis's fatigue road is 100 m of the LTC (Leyland Technical Centre) pavé durability track,
measured at 34 km/h and proprietary (Ch. 4 Sec. 4.5, Ch. 6 Sec. 6.4). This module builds a
substitute (a deviation, flagged in the scenarios): square setts laid in courses across the
road, crossed by each wheel path one after the other, on a base road with its own long waves.

Profile of one wheel track, height z [m] against distance x [m]::

    stone i: top from a_i to b_i = a_i + L_i, then a joint of width w to a_(i+1) = b_i + w
    on the stone:  z = h_i + c * 4 u (1 - u),              u = (x - a_i) / L_i  in [0, 1]
    in the joint:  z = (1 - v) h_i + v h_(i+1) - d (1 - cos 2 pi v) / 2,  v = (x - b_i) / w

a crowned stone, a smooth (cosine) joint of depth d below the chord of the two stone edges,
the next stone a step h_(i+1) - h_i higher. Lengths L_i are Gamma (mean L, std s_L), heights
h_i independent normal (0, s_h^2), the first stone at a random phase. The long waves z_lw(x)
are a thesis Eq. 4.10 road, S(n) = G n^-p (:mod:`nodes.tyre_road.iso8608`); the track is
z_lw + z_stones, shifted to z(0) = 0; left and right have their own stones and long waves
with the power-law road's ``correlation``.

In the 0-20 Hz ride band (n < 2.1 cycles/m at 34 km/h; the stone pitch P = L + w, ~0.165 m,
is at 57 Hz) the stones act through their random heights: a one-sided PSD at low n of about
2 s_h^2 E[P^2] / E[P] (white displacement, 8.5e-6 m^3 for s_h = 5 mm; tests/roads/
test_cobblestone.py), driving the wheel hop, while the long waves drive the body. So s_h and G
are calibrated against Table 4.5 (hub and body 0-20 Hz RMS of the passive realistic corner,
``python -m bench calibrate-pave``, ``docs/vehicles_roads.md``); the others are fixed from the
geometry of Belgian block (:class:`PaveParameters`).

Sampling: every :data:`DX` = 2 mm (7 points across the 15 mm joint, the crown's parabola to
0.1 % of c), linearly interpolated by :class:`~nodes.tyre_road.roads.SampledRoad`; a
point-contact tyre sees the joints at the spacing v h (18.9 mm at 34 km/h and 2 ms, as the
thesis's own 2 ms digitisation).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .iso8608 import DEFAULT_N_MAX, DEFAULT_N_MIN, DEFAULT_WAVINESS, power_law_psd, random_profile
from .roads import SampledRoad

DX = 0.002
"""Tabulation step of the profile [m]."""


@dataclass(frozen=True)
class PaveParameters:
    """Geometry of the synthetic pavé (SI units; checked by the ``[road]`` reader,
    :mod:`.config`). Defaults and their reasoning:

    * ``stone_length`` L [m], mean top length along the wheel path: Belgian block setts are
      0.10-0.20 m (100 x 100 ... 150 x 200 mm): 0.15 m; ``stone_length_std`` s_L [m], Gamma
      distributed: hand-laid setts of one size class differ by 10-20 % (and a wheel path
      crosses the courses at slightly varying angles): 0.03 m (20 %).
    * ``joint_width`` w [m], the gap between two stones: the 10-20 mm range, middle 0.015 m;
      ``joint_depth`` d [m], the dip the contact point follows: a worn joint is 10-20 mm deep
      but filled with grit and bridged by the tyre (a rigid ring of R = 0.3 m sinks w^2 /
      (8 R) = 0.1 mm into 15 mm, the tread a few mm): 0.005 m.
    * ``stone_height_std`` s_h [m], of a stone's top about the base road (settled, tilted,
      worn stones; the step between neighbours is sqrt(2) s_h): CALIBRATED (hub 0-20 Hz RMS,
      Table 4.5) 0.0095 m, steps of 13 mm standard deviation, the top of the Belgian block
      range (:data:`DEFAULTS`); ``crown`` c [m], the parabolic dome of a stone's top above its
      edges: 0.003 m over 0.15 m.
    * long waves: ``G`` [m^(3-p)], S(n) = G n^-p at n = 1 cycle/m, CALIBRATED (body 0-20 Hz
      RMS, Table 4.5) 1.5e-5, three times the thesis's "rough minor road" 5e-6;
      ``waviness`` p, the thesis's 2.5 (Eq. 4.10); ``band`` (n_min, n_max) [cycles/m], the ISO
      8608 band as the power-law road's; ``correlation`` of left and right ("identical",
      "independent" or rho in [0, 1]; the stones are always independent), "independent" (the
      LTC tracks are distinct, so the body bounces, pitches and rolls, Sec. 4.5).
    """

    stone_length: float = 0.15
    stone_length_std: float = 0.03
    joint_width: float = 0.015
    joint_depth: float = 0.005
    stone_height_std: float = 0.0095
    crown: float = 0.003
    G: float = 1.5e-5
    waviness: float = DEFAULT_WAVINESS
    band: tuple[float, float] = (DEFAULT_N_MIN, DEFAULT_N_MAX)
    correlation: str | float = "independent"


DEFAULTS = PaveParameters()
"""The calibrated pavé (``python -m bench calibrate-pave --search``): the passive realistic
corner of ``scenarios/thesis/ch6_realistic_qvm.toml`` over 100 m, seeds 1-3, gives 0-20 Hz
RMS hub 59.6 +- 3.7 and body 3.22 +- 0.26 m/s^2 at (G, s_h) = (1.503e-5, 9.54 mm), Table 4.5:
59.2 / 3.23; fixed at the rounded (1.5e-5, 9.5 mm) (per seed: ``docs/vehicles_roads.md``).
Only these two ride numbers were used: no fatigue life enters."""


def stone_layout(length: float, rng: np.random.Generator, p: PaveParameters
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stones covering [0, length]: start a_i [m], top length L_i [m], top height h_i [m].

    The first stone starts at -U(0, L_0 + w) (a random phase); the last one starts beyond
    ``length``.
    """
    n = int(np.ceil(length / (p.stone_length + p.joint_width) * 1.3)) + 8
    if p.stone_length_std > 0:
        k = (p.stone_length / p.stone_length_std) ** 2  # Gamma shape: mean L, std s_L
        lengths = rng.gamma(k, p.stone_length / k, size=n)
    else:
        lengths = np.full(n, p.stone_length)
    heights = rng.normal(0.0, p.stone_height_std, size=n) if p.stone_height_std > 0 \
        else np.zeros(n)
    phase = rng.uniform(0.0, lengths[0] + p.joint_width)
    starts = np.concatenate(([0.0], np.cumsum(lengths[:-1] + p.joint_width))) - phase
    beyond = np.flatnonzero(starts > length)
    if beyond.size == 0:  # cannot happen with the 1.3 x margin on the count
        raise RuntimeError("stone_layout: too few stones drawn")
    keep = slice(0, beyond[0] + 1)  # up to the first stone starting beyond the end
    return starts[keep], lengths[keep], heights[keep]


def stone_heights(x: np.ndarray, starts: np.ndarray, lengths: np.ndarray,
                  heights: np.ndarray, p: PaveParameters) -> np.ndarray:
    """Height [m] of the stone surface (stones + joints, no long waves) at distances ``x``."""
    x = np.asarray(x, dtype=float)
    i = np.clip(np.searchsorted(starts, x, side="right") - 1, 0, starts.size - 1)
    local = x - starts[i]
    on_stone = local <= lengths[i]
    u = np.clip(local / lengths[i], 0.0, 1.0)
    z_stone = heights[i] + p.crown * 4.0 * u * (1.0 - u)
    v = np.clip((local - lengths[i]) / p.joint_width, 0.0, 1.0)
    h_next = heights[np.minimum(i + 1, heights.size - 1)]
    z_joint = (1.0 - v) * heights[i] + v * h_next \
        - p.joint_depth * 0.5 * (1.0 - np.cos(2.0 * np.pi * v))
    return np.where(on_stone, z_stone, z_joint)


def pave_profile(length: float, seed: int, p: PaveParameters = DEFAULTS
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                            dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]]:
    """Heights (x, z_left, z_right) [m] of a pavé track ``length`` m long, every :data:`DX`.

    Also returns the stone layouts ({"left": (starts, lengths, heights), "right": ...}) for
    checks. ``seed`` draws the long waves (as the power-law road of that seed) and, from
    independent streams, the stones of each track. z(0) = 0 on both tracks.
    """
    x_lw, lw_l, lw_r = random_profile(power_law_psd(p.G, p.waviness), length, seed,
                                      p.correlation, p.band[0], p.band[1])
    x = np.arange(int(np.ceil(length / DX)) + 1) * DX
    tracks, layouts = [], {}
    for name, lw, stream in (("left", lw_l, 1), ("right", lw_r, 2)):
        layout = stone_layout(x[-1], np.random.default_rng([seed, stream]), p)
        z = np.interp(x, x_lw, lw) + stone_heights(x, *layout, p)
        tracks.append(z - z[0])
        layouts[name] = layout
    return x, tracks[0], tracks[1], layouts


def pave_road(length: float, speed: float, seed: int, p: PaveParameters = DEFAULTS
              ) -> SampledRoad:
    """A :class:`SampledRoad` of the synthetic pavé, ``length`` m, driven at ``speed`` m/s."""
    x, zl, zr, _ = pave_profile(length, seed, p)
    return SampledRoad(x=x, z_left=zl, z_right=zr, speed=speed, length=length, name="pave")
