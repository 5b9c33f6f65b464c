"""Whole-signal ride metrics: the oracle the streamed estimators of nodes/recorder/ride_stream.py
(the product's one implementation) are checked against. What they were before the two became
one (nodes/recorder/ride_metrics.py until 2026-12-06): scipy's resample_poly and periodogram
on the whole record, Wk applied on a zero-padded FFT, np.gradient for the jerk."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from scipy.integrate import trapezoid
from scipy.signal import periodogram, resample_poly

from nodes.recorder import ride_metrics as rm


def rms(x: np.ndarray) -> float:
    """Root mean square of ``x`` (same unit as x)."""
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        raise ValueError("rms of an empty signal")
    return float(np.sqrt(np.mean(x * x)))


def resample_to(t: np.ndarray, x: np.ndarray, fs_out: float = rm.THESIS_FS) -> np.ndarray:
    """``scipy.signal.resample_poly`` to ``fs_out`` (Hz), Kaiser beta 8; a copy at fs_out."""
    from fractions import Fraction

    x = np.asarray(x, dtype=float)
    fs_in = rm.sample_rate(t)
    if abs(fs_in - fs_out) <= 1e-6 * fs_out:
        return x.copy()
    ratio = Fraction(fs_out / fs_in).limit_denominator(10000)
    return resample_poly(x, ratio.numerator, ratio.denominator,
                         window=("kaiser", rm._AA_KAISER_BETA))


def matlab_periodogram(x: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """(f in Hz, P in unit²/Hz) as MATLAB's ``periodogram(x, [], [], fs)`` (thesis Eq 4.8):
    rectangular window, no detrend, ``nfft = max(256, 2^nextpow2(N))``, one-sided density."""
    x = np.asarray(x, dtype=float)
    nfft = max(256, 1 << int(np.ceil(np.log2(x.size))))
    return periodogram(x, fs=fs, window="boxcar", nfft=nfft, detrend=False,
                       return_onesided=True, scaling="density")


def periodogram_band_rms(x: np.ndarray, fs: float, band: tuple[float, float]) -> float:
    f, P = matlab_periodogram(x, fs)
    keep = (f >= band[0]) & (f <= band[1])
    return float(np.sqrt(trapezoid(P[keep], f[keep])))


def iso2631_wk(a: np.ndarray, fs: float) -> np.ndarray:
    """``a`` (m/s²) at ``fs`` (Hz) weighted by Wk (m/s²), on a zero-padded FFT (no warping)."""
    a = np.asarray(a, dtype=float)
    n = a.size
    nfft = 1 << int(np.ceil(np.log2(max(2 * n, 2))))
    f = np.fft.rfftfreq(nfft, 1.0 / fs)
    return np.fft.irfft(np.fft.rfft(a, nfft) * rm.wk_response(f), nfft)[:n]


def iso2631_wk_weighted_rms(a: np.ndarray, fs: float) -> float:
    return rms(iso2631_wk(a, fs))


def jerk(a: np.ndarray, fs: float) -> np.ndarray:
    """Jerk da/dt (m/s³) by central differences (one-sided at the ends)."""
    return np.gradient(np.asarray(a, dtype=float), 1.0 / fs)


def working_space(z_b: np.ndarray, z_w: np.ndarray) -> float:
    """Max minus min of the suspension compression ``z_w - z_b`` (m)."""
    d = np.asarray(z_w, dtype=float) - np.asarray(z_b, dtype=float)
    return float(np.max(d) - np.min(d))


def dynamic_tyre_load(F_t: np.ndarray, F_static: float | None = None) -> np.ndarray:
    """``F_t - F_static`` (N); the static load defaults to the mean of F_t."""
    F_t = np.asarray(F_t, dtype=float)
    return F_t - (float(np.mean(F_t)) if F_static is None else float(F_static))


def metric_values(table: Mapping[str, np.ndarray], band_hz: tuple[float, float] = rm.THESIS_BAND,
                  fs_out: float = rm.THESIS_FS) -> dict[str, tuple[float, str, str]]:
    """The keys, values, units and labels of ``rm.metric_values`` from the whole columns."""
    t = np.asarray(table["t"], dtype=float)
    f1, f2 = (float(b) for b in band_hz)
    m: dict[str, tuple[float, str, str]] = {}

    def banded(name: str, unit: str, full: bool, body: bool, b16: bool) -> None:
        for lab, a in rm.columns(table, f"plant/response/{name}"):
            a5, key, u = resample_to(t, a, fs_out), f"{name}{lab}", f"[{unit}]"
            m[f"{key}_rms"] = (periodogram_band_rms(a5, fs_out, (f1, f2)), unit,
                               f"{key} RMS {f1:g}-{f2:g} Hz {u}")
            if b16 and (f1, f2) != rm.BAND_16:
                m[f"{key}_rms_0_16"] = (periodogram_band_rms(a5, fs_out, rm.BAND_16), unit,
                                        f"{key} RMS 0-16 Hz {u}")
            if full:
                m[f"{key}_rms_full"] = (rms(a), unit, f"{key} RMS full band {u}")
            if body:
                m[f"{key}_wk_rms"] = (iso2631_wk_weighted_rms(a5, fs_out), unit,
                                      f"{key} Wk RMS {u}")
                m[f"jerk_b{lab}_rms"] = (rms(jerk(a5, fs_out)), "m/s3",
                                         f"jerk_b{lab} RMS [m/s3]")

    banded("a_b", "m/s2", True, True, True)
    banded("a_w", "m/s2", True, False, False)
    for name in rm.ARM_ACCEL_FIELDS:
        banded(name, "m/s2", False, False, False)
    for name in rm.ROTATION_FIELDS:
        banded(name, "rad/s2", False, False, True)
    zb, zw = rm.columns(table, "plant/state/z_b"), rm.columns(table, "plant/state/z_w")
    for (lab, b), (_, w) in zip(zb, zw, strict=False):
        m[f"sws{lab}"] = (1e3 * working_space(b, w), "mm", f"SWS{lab} [mm]")
        m[f"defl{lab}_rms"] = (1e3 * rms(w - b), "mm", f"defl{lab} RMS [mm]")
    for lab, F in rm.columns(table, "tyre_road/force/F_t"):
        m[f"dtl{lab}_rms"] = (rms(dynamic_tyre_load(F)), "N", f"DTL{lab} RMS [N]")
    for lab, F in rm.columns(table, "controller/force/F_d"):
        m[f"f_d{lab}_rms"] = (rms(F), "N", f"F_d{lab} RMS [N]")
    return m
