"""Frequency-domain fatigue: a stress history's PSD -> the density of its cycle
amplitudes (Dirlik; Tovo-Benasciutti) -> Miner damage. Pure numerics, no I/O.

Symbols (SI: stress in Pa, frequency f in Hz, time in s):

* G(f) [Pa^2/Hz]: the one-sided PSD of the signed equivalent stress, by Welch's method
  (:func:`welch_psd`: Hann window, segments of `SEGMENT_S` = 1 s rounded to a power of two of
  samples, 50 % overlap, each segment's mean removed, ``scipy.signal.welch`` with
  ``scaling="density"``); the history's mean is kept apart as the cycles' mean stress.
* m_n = int f^n G(f) df [Pa^2 Hz^n]: spectral moments (trapezoid over Welch's frequencies).
* nu_0 = sqrt(m2 / m0): mean up-crossings per second; nu_p = sqrt(m4 / m2): peaks per second.
* alpha_1 = m1 / sqrt(m0 m2), alpha_2 = m2 / sqrt(m0 m4): bandwidth parameters (alpha_2 is
  Dirlik's gamma, the irregularity factor nu_0 / nu_p).
* Cycle densities n(a) [1/(s Pa)]: expected cycles per second of amplitude a per Pa, so that
  the damage rate is int n(a) / N(a) da (Palmgren-Miner, N(a) the cycles to failure of a
  cycle of amplitude a about the history's mean, from the same S-N curve, mean-stress rule and
  endurance rule as the rainflow method: :func:`nodes.fatigue.lib.damage.cycle_reversals`).

**Dirlik** (T. Dirlik, "Application of computers in fatigue analysis", PhD thesis, University
of Warwick, 1985; as written in Zorman, Slavic & Boltezar, MSSP 2023, and FLife's
``Dirlik``): with x_m = (m1 / m0) sqrt(m2 / m4), gamma = alpha_2,

    D1 = 2 (x_m - gamma^2) / (1 + gamma^2),   R = (gamma - x_m - D1^2) / (1 - gamma - D1 + D1^2),
    D2 = (1 - gamma - D1 + D1^2) / (1 - R),    D3 = 1 - D1 - D2,
    Q = 1.25 (gamma - D3 - D2 R) / D1,          Z = a / sqrt(m0),
    p(a) = [D1/Q e^(-Z/Q) + D2 Z/R^2 e^(-Z^2/(2 R^2)) + D3 Z e^(-Z^2/2)] / sqrt(m0),

the density of the rainflow cycle amplitudes, cycles at the peak rate: n(a) = nu_p p(a).

**Tovo-Benasciutti** (D. Benasciutti, R. Tovo, "Spectral methods for lifetime prediction under
wide-band stationary random processes", Int. J. Fatigue 27 (2005) 867-877; their method 2 as
FLife's ``TovoBenasciutti``): the damage D_TB = [b + (1 - b) alpha_2^(k-1)] D_NB between the
narrow-band (Rayleigh amplitudes, sigma = sqrt(m0), at nu_0) and the range-count (Rayleigh of
alpha_2 sigma, at nu_p) bounds, with

    b = (alpha_1 - alpha_2) [1.112 (1 + alpha_1 alpha_2 - (alpha_1 + alpha_2))
        e^(2.11 alpha_2) + (alpha_1 - alpha_2)] / (alpha_2 - 1)^2,

written as a cycle density, so that any S-N curve integrates it:
n(a) = b nu_0 Ray(a; sqrt(m0)) + (1 - b) nu_p Ray(a; alpha_2 sqrt(m0)),
Ray(a; s) = a / s^2 e^(-a^2 / (2 s^2)). Its D is D_TB for a power-law curve.

Both assume a stationary Gaussian history; a road's arm stress is neither quite (the setts'
impacts): the docs table (docs/fatigue.md, "Frequency-domain life") gives the ratio to rainflow.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

SEGMENT_S = 1.0
"""Welch segment length [s] (rounded to a power of two of samples; at most the history)."""
METHODS = ("dirlik", "tovo_benasciutti")
Z_MAX = 80.0
"""Upper end of the amplitude grid in units of sqrt(m0) times max(1, Q): Dirlik's exponential
term decays as e^(-Z/Q), and a steel curve's k ~ 12 puts the damage integrand's peak at k Q."""
N_GRID = 2000
"""Amplitude grid points per node (trapezoid)."""


def welch_psd(x: np.ndarray, fs: float, segment_s: float = SEGMENT_S
              ) -> tuple[np.ndarray, np.ndarray]:
    """(f [Hz], G [unit^2/Hz] of shape (..., n_f)) of histories ``x`` (..., n_samples) sampled
    at ``fs`` [Hz]: Welch, Hann, 50 % overlap, constant detrend (module docstring)."""
    from scipy.signal import welch

    n = x.shape[-1]
    nper = int(min(n, 2 ** int(round(np.log2(max(fs * segment_s, 8.0))))))
    return welch(x, fs=fs, window="hann", nperseg=nper, noverlap=nper // 2,
                 detrend="constant", scaling="density", axis=-1)


def moments(f: np.ndarray, G: np.ndarray) -> np.ndarray:
    """Spectral moments m0, m1, m2, m4 (shape (4, ...)) of the one-sided PSD ``G`` at ``f``."""
    return np.stack([np.trapezoid(G * f ** n, f, axis=-1) for n in (0, 1, 2, 4)])


def dirlik_coefficients(m: np.ndarray) -> dict[str, np.ndarray]:
    """D1, D2, D3, Q, R and the rates nu_p, nu_0 [1/s] from the moments (module docstring)."""
    m0, m1, m2, m4 = m
    x_m = m1 / m0 * np.sqrt(m2 / m4)
    g = m2 / np.sqrt(m0 * m4)
    D1 = 2 * (x_m - g ** 2) / (1 + g ** 2)
    R = (g - x_m - D1 ** 2) / (1 - g - D1 + D1 ** 2)
    D2 = (1 - g - D1 + D1 ** 2) / (1 - R)
    D3 = 1 - D1 - D2
    Q = 1.25 * (g - D3 - D2 * R) / D1
    return {"D1": D1, "D2": D2, "D3": D3, "Q": Q, "R": R, "nu_p": np.sqrt(m4 / m2),
            "nu_0": np.sqrt(m2 / m0)}


def dirlik_pdf(a: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Dirlik's density p(a) [1/Pa] of the cycle amplitudes ``a`` [Pa] (broadcast against the
    moments' trailing shape)."""
    c = dirlik_coefficients(m)
    s = np.sqrt(m[0])
    Z = a / s
    Q, R = c["Q"], c["R"]
    return (c["D1"] / Q * np.exp(-Z / Q) + c["D2"] * Z / R ** 2 * np.exp(-Z ** 2 / (2 * R ** 2))
            + c["D3"] * Z * np.exp(-Z ** 2 / 2)) / s


def tovo_benasciutti_b(m: np.ndarray) -> np.ndarray:
    """The weight b of Tovo-Benasciutti's method 2 (module docstring)."""
    m0, m1, m2, m4 = m
    a1 = m1 / np.sqrt(m0 * m2)
    a2 = m2 / np.sqrt(m0 * m4)
    return (a1 - a2) * (1.112 * (1 + a1 * a2 - (a1 + a2)) * np.exp(2.11 * a2)
                        + (a1 - a2)) / (a2 - 1) ** 2


def cycle_density(method: str, a: np.ndarray, m: np.ndarray) -> np.ndarray:
    """n(a) [1/(s Pa)]: expected cycles per second of amplitude ``a`` [Pa], per Pa."""
    m0, _m1, m2, m4 = m
    if method == "dirlik":
        return np.sqrt(m4 / m2) * dirlik_pdf(a, m)
    if method != "tovo_benasciutti":
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    b = tovo_benasciutti_b(m)
    s = np.sqrt(m0)
    a2 = m2 / np.sqrt(m0 * m4)

    def ray(scale: np.ndarray) -> np.ndarray:
        return a / scale ** 2 * np.exp(-a ** 2 / (2 * scale ** 2))
    return b * np.sqrt(m2 / m0) * ray(s) + (1 - b) * np.sqrt(m4 / m2) * ray(a2 * s)


def damage_rate(method: str, m: np.ndarray, mean: np.ndarray,
                reversals: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> np.ndarray:
    """Miner damage per second [1/s] of each history (moments ``m`` (4, k), means ``mean``
    (k,) [Pa]): int n(a) / N(a) da on a grid of `N_GRID` amplitudes up to `Z_MAX` max(1, Q)
    sqrt(m0), N = reversals(mean - a, mean + a) / 2 (a cycle of amplitude a about the mean).
    A history without variance (m0 = 0) has no damage."""
    m = np.asarray(m, dtype=float)
    live = m[0] > 0
    out = np.zeros(m.shape[1])
    if not live.any():
        return out
    ml = m[:, live]
    q = np.abs(dirlik_coefficients(ml)["Q"]) if method == "dirlik" else np.ones(ml.shape[1])
    top = Z_MAX * np.maximum(1.0, np.nan_to_num(q, nan=1.0)) * np.sqrt(ml[0])
    a = np.linspace(0.0, 1.0, N_GRID)[None, :] * top[:, None]  # (k, N_GRID)
    n = cycle_density(method, a, ml[:, :, None])
    mu = np.asarray(mean, dtype=float)[live][:, None]
    with np.errstate(divide="ignore", over="ignore"):
        inv_N = 2.0 / reversals(mu - a, mu + a)
    out[live] = np.trapezoid(np.where(n > 0, n * inv_N, 0.0), a, axis=1)
    return out
