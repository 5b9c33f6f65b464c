"""Random roads with the thesis's power-law roughness spectrum (Eq. 4.10).

The thesis (Ch. 4 Sec. 4.4, after its ref. [30]) describes road roughness by

    S(n) = G n^(-p),   n [cycles/m],  S [m^3/cycle] = [m^2 / (cycles/m)],

with p = 2.5 and G from 1e-7 m^1.5 (smooth motorway) to 5e-6 m^1.5 (rough minor road); G is
the PSD at n = 1 cycle/m, so its unit is m^(3-p) (m^0.5 for p = 2.5; written "G" here with the
exponent understood). The thesis does not use it to generate roads (its roads were measured
and are proprietary); here it is the substitute for the MIRA smooth track and the long-wave
part of the LTC pavé substitute (:mod:`nodes.tyre_road.cobblestone`).

Choices the thesis does not fix, made here:

* **S is one-sided** (the variance is the integral of S over n > 0), as in ISO 8608 and in
  Wong, *Theory of Ground Vehicles*, whose table of road spectra the G range matches.
* **Band** default [0.011, 2.83] cycles/m, the ISO 8608 classification band (0.1-26.7 Hz at
  34 km/h, covering the 0-25 Hz ride band of Sec. 4.5). A power law with p > 1 has infinite
  variance towards n -> 0, so the band's lower end fixes the road's amplitude of long waves:
  keep it unless the length of the run calls for longer waves.
* **Generator** the seeded sum of sinusoids on an FFT grid of :func:`nodes.tyre_road.iso8608.
  random_profile` (deterministic amplitudes, random phases), with the same left/right
  ``correlation`` options ("identical", "independent", or rho in [0, 1]).

Check (``tests/roads/test_power_law.py``): the Welch PSD of a 2000 m track, integrated over
octave bands, matches the integral of G n^-p within 5 %.
"""

from __future__ import annotations

import numpy as np

from .iso8608 import DEFAULT_N_MAX, DEFAULT_N_MIN, random_profile
from .roads import SampledRoad

DEFAULT_WAVINESS = 2.5
"""The thesis's exponent p (Eq. 4.10)."""

def power_law_psd(n: np.ndarray, G: float, p: float = DEFAULT_WAVINESS) -> np.ndarray:
    """S(n) = G n^-p [m^3/cycle] at spatial frequencies ``n`` [cycles/m] (> 0)."""
    return G * np.asarray(n, dtype=float) ** (-p)


def power_law_profile(G: float, length: float, seed: int, p: float = DEFAULT_WAVINESS,
                      correlation: str | float = "independent",
                      n_min: float = DEFAULT_N_MIN, n_max: float = DEFAULT_N_MAX,
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Heights (x [m], z_left [m], z_right [m]) of an Eq. 4.10 road at least ``length`` m long.

    ``G`` [m^(3-p)] > 0, ``p`` the waviness, ``seed`` for the phases, band [n_min, n_max]
    [cycles/m]; z(0) = 0 on both tracks. Sampled every 1 / (20 n_max) m.
    """
    if not G > 0:
        raise ValueError(f"G must be > 0, got {G}")
    return random_profile(lambda n: power_law_psd(n, G, p), length, seed, correlation,
                          n_min, n_max)


def power_law_road(G: float, length: float, speed: float, seed: int,
                   p: float = DEFAULT_WAVINESS, correlation: str | float = "independent",
                   n_min: float = DEFAULT_N_MIN, n_max: float = DEFAULT_N_MAX) -> SampledRoad:
    """A :class:`SampledRoad` of Eq. 4.10 (``G``, ``p``), ``length`` m, driven at ``speed`` m/s."""
    x, zl, zr = power_law_profile(G, length, seed, p, correlation, n_min, n_max)
    return SampledRoad(x=x, z_left=zl, z_right=zr, speed=speed, length=length,
                       name="power_law")
