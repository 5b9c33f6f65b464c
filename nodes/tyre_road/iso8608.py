"""Random road profiles (substitutes for the thesis's proprietary MIRA and LTC pavé
measurements, Ch. 4 Sec. 4.5; flagged as a deviation): the ISO 8608 roughness classes A-H and
the thesis's power law (Eq. 4.10), by one generator.

ISO 8608 describes a road by the one-sided displacement PSD in spatial frequency n [cycles/m]

    G_d(n) = G_d(n0) (n / n0)^(-w),   n0 = 0.1 cycles/m,  w = 2,

with the class geometric-mean values G_d(n0) [m^3] below (class A 16e-6 ... H 262144e-6; each
class is a factor 4 above the previous one and spans a factor 2 either side of its mean).
(The thesis's Eq. 4.10, S(n) = G n^-2.5, is the same family with a different waviness.)

Method: **sum of sinusoids with random phases on an FFT grid** (deterministic amplitudes)

    z(x) = sum_k sqrt(2 G_d(n_k) dn) cos(2 pi n_k x + phi_k),   n_min <= n_k <= n_max,

with n_k = k dn, dn = 1 / L_gen, phases phi_k uniform on [0, 2 pi) from a seeded PCG64
(the same road for the same class, seed, band and length), evaluated by an inverse real FFT on
a grid dx <= 1 / (20 n_max), linearly interpolated (< 1 % PSD loss at n_max); each track
shifted to z(0) = 0.

Left/right tracks (``correlation``): ``"identical"`` (pure heave/pitch input),
``"independent"`` (own phases, coherence 0) or rho in [0, 1]: z_R = rho z_L + sqrt(1 - rho^2)
z_indep, each track keeping the PSD (in expectation), the coherence rho^2 at every n.

The thesis's power law (Ch. 4 Sec. 4.4, after its ref. [30], ``type = "power_law"``):

    S(n) = G n^(-p),   n [cycles/m],  S [m^3/cycle] = [m^2 / (cycles/m)],

with p = 2.5 and G from 1e-7 m^1.5 (smooth motorway) to 5e-6 m^1.5 (rough minor road); G is
the PSD at n = 1 cycle/m, so its unit is m^(3-p) (m^0.5 for p = 2.5; written "G" here with the
exponent understood). The thesis does not use it to generate roads (its roads were measured);
here it is the substitute for the MIRA smooth track and the long-wave part of the LTC pavé
substitute (:mod:`nodes.tyre_road.cobblestone`). Choices the thesis does not fix, made here:

* **S is one-sided** (the variance is the integral of S over n > 0), as in ISO 8608 and in
  Wong, *Theory of Ground Vehicles*, whose table of road spectra the G range matches.
* **Band** default [0.011, 2.83] cycles/m, the ISO 8608 classification band (0.1-26.7 Hz at
  34 km/h, covering the 0-25 Hz ride band of Sec. 4.5). A power law with p > 1 has infinite
  variance towards n -> 0, so the band's lower end fixes the road's amplitude of long waves:
  keep it unless the length of the run calls for longer waves.

Checks: ``tests/roads/test_iso8608.py`` (the class PSD) and ``tests/roads/test_power_law.py``
(the Welch PSD of a 2000 m track, integrated over octave bands, matches the integral of G n^-p
within 5 %). The band, the correlation and the class are checked by the ``[road]`` reader
(:mod:`.config`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .roads import SampledRoad

N0 = 0.1
"""Reference spatial frequency n0 [cycles/m]."""

WAVINESS = 2.0
"""ISO 8608 waviness w (slope of log G_d against log n)."""

GD_N0 = {"A": 16e-6, "B": 64e-6, "C": 256e-6, "D": 1024e-6,
         "E": 4096e-6, "F": 16384e-6, "G": 65536e-6, "H": 262144e-6}
"""ISO 8608 class geometric-mean G_d(n0) [m^3]."""

DEFAULT_N_MIN = 0.011
DEFAULT_N_MAX = 2.83
"""ISO 8608 classification band [cycles/m] (at 34 km/h: 0.1-26.7 Hz, the ride band)."""


DEFAULT_WAVINESS = 2.5
"""The thesis's exponent p (Eq. 4.10)."""


def iso8608_psd(road_class: str) -> Callable[[np.ndarray], np.ndarray]:
    """G_d(n) [m^3] of the class's geometric mean, a function of n [cycles/m]."""
    return lambda n: GD_N0[road_class] * (np.asarray(n, dtype=float) / N0) ** (-WAVINESS)


def power_law_psd(G: float, p: float = DEFAULT_WAVINESS) -> Callable[[np.ndarray], np.ndarray]:
    """S(n) = G n^-p [m^3/cycle] (thesis Eq. 4.10), a function of n [cycles/m] (> 0)."""
    return lambda n: G * np.asarray(n, dtype=float) ** (-p)


def _random_track(gd: np.ndarray, rng: np.random.Generator, n_grid: int) -> np.ndarray:
    """Inverse-rFFT of sqrt(2 G dn) amplitudes with random phases -> heights on the grid."""
    phases = rng.uniform(0.0, 2.0 * np.pi, size=gd.size)
    amp = np.sqrt(2.0 * gd)  # gd already multiplied by dn
    spec = amp * np.exp(1j * phases)
    # irfft computes (1/N) sum c_k e^{i...} over the Hermitian spectrum -> factor N/2 per side
    return np.fft.irfft(spec * n_grid / 2.0, n=n_grid)


def random_profile(psd: Callable[[np.ndarray], np.ndarray], length: float, seed: int,
                   correlation: str | float = "independent",
                   n_min: float = DEFAULT_N_MIN, n_max: float = DEFAULT_N_MAX,
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Heights (x, z_left, z_right) [m] of a random road with one-sided displacement PSD
    ``psd(n)`` [m^3] (n [cycles/m], n > 0) on the band [n_min, n_max], at least ``length`` m long.

    The sum-of-sinusoids method of the module docstring; the generated length
    L_gen >= max(length, 2 / n_min) so that the lowest frequency of the band is represented by at
    least two spectral lines.
    """
    dx = 1.0 / (20.0 * n_max)
    l_gen = max(float(length), 2.0 / n_min)
    n_grid = int(2 ** np.ceil(np.log2(l_gen / dx)))
    dn = 1.0 / (n_grid * dx)
    n = np.arange(n_grid // 2 + 1) * dn
    band = (n >= n_min) & (n <= n_max)
    gd = np.where(band, psd(np.where(n > 0, n, 1.0)) * dn, 0.0)
    rng = np.random.default_rng(seed)
    z_l = _random_track(gd, rng, n_grid)
    if correlation == "identical":
        z_r = z_l.copy()
    else:
        z_ind = _random_track(gd, rng, n_grid)
        if correlation == "independent":
            z_r = z_ind
        else:
            rho = float(correlation)
            z_r = rho * z_l + np.sqrt(1.0 - rho * rho) * z_ind
    x = np.arange(n_grid) * dx
    return x, z_l - z_l[0], z_r - z_r[0]


def random_road(psd: Callable[[np.ndarray], np.ndarray], length: float, speed: float,
                seed: int, correlation: str | float, n_min: float, n_max: float,
                name: str) -> SampledRoad:
    """A :class:`SampledRoad` of :func:`random_profile`, ``length`` m, driven at ``speed`` m/s."""
    x, zl, zr = random_profile(psd, length, seed, correlation, n_min, n_max)
    return SampledRoad(x=x, z_left=zl, z_right=zr, speed=speed, length=length, name=name)
