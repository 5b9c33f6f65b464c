"""Ride metrics of a recorded run: RMS, PSD band RMS, ISO 2631-1 Wk weighting, suspension
working space, dynamic tyre load, jerk; and a comparison table of runs (thesis Tables 5.3-5.6).

Pure functions over numpy arrays. Sampling is given as ``fs`` (Hz) or taken from a run
table's ``t`` column (s). Frequency bands are in Hz, never in bin indices.

* The thesis's RMS (Eq 4.8/4.9, App. IV; :func:`thesis_band_rms`): the signal resampled
  anti-aliased to 500 Hz (a 2 ms run passes unchanged; a 0.5 ms MR run is low-passed first,
  so its switching chatter above 250 Hz is not counted), MATLAB's default periodogram
  (rectangular window, no detrend, nfft = 2^nextpow2(N)), integrated with the trapezoidal
  rule over the bins of ``[f1, f2]`` (0-20 Hz, or 0-16 Hz for Tables 5.7-5.10), square root.
  This is the headline body RMS of a run (:func:`metric_values` key ``a_b_rms``); the
  time-domain RMS at the run's own rate is ``a_b_rms_full``.
* :func:`band_rms` / :func:`psd`: the same band integral at the signal's own rate, mean
  removed (kept for signals that are not run tables).
* ``% improvement`` (thesis Eq 5.13): ``(baseline - run) / baseline * 100``; positive = less.
* ISO 2631-1:1997 Wk (vertical, seated/standing/recumbent): band limiting (high-pass 0.4 Hz,
  low-pass 100 Hz, both 2nd-order Butterworth, Q = 1/sqrt(2)) times the acceleration-velocity
  transition (f3 = f4 = 12.5 Hz, Q4 = 0.63) times the upward step (f5 = 2.37 Hz, Q5 = 0.91,
  f6 = 3.35 Hz, Q6 = 0.91), applied exactly in the frequency domain (zero-padded FFT).

These take whole signals; :mod:`.ride_stream` computes the same metrics from a table read in
row batches (``suscosim report``: the same periodogram, to rounding; Wk to ~1e-7).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from fractions import Fraction

import numpy as np
from scipy.integrate import trapezoid
from scipy.signal import periodogram, resample_poly

Table = Mapping[str, np.ndarray]

# ISO 2631-1:1997 Annex A, Table A.1, weighting Wk
WK_F1, WK_F2 = 0.4, 100.0  # Hz, band limits
WK_Q12 = 1.0 / np.sqrt(2.0)
WK_F3, WK_F4, WK_Q4 = 12.5, 12.5, 0.63  # acceleration-velocity transition
WK_F5, WK_Q5, WK_F6, WK_Q6 = 2.37, 0.91, 3.35, 0.91  # upward step


# ----------------------------------------------------------------------------- basics


def rms(x: np.ndarray) -> float:
    """Root mean square of ``x`` (same unit as x)."""
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        raise ValueError("rms of an empty signal")
    return float(np.sqrt(np.mean(x * x)))


def sample_rate(t: np.ndarray) -> float:
    """Sampling frequency (Hz) of a uniformly sampled time column ``t`` (s)."""
    t = np.asarray(t, dtype=float)
    if t.size < 2:
        raise ValueError("need at least 2 samples to know the sampling rate")
    dt = np.diff(t)
    step = float(np.median(dt))
    if step <= 0.0 or np.max(np.abs(dt - step)) > 0.01 * step:
        raise ValueError("time column is not uniformly sampled (a run with missing steps?)")
    return 1.0 / step


def psd(
    x: np.ndarray, fs: float, band_hz: tuple[float, float] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """One-sided periodogram PSD of ``x`` (unit²/Hz), mean removed, rectangular window.

    Args:
        x: signal sampled at ``fs`` (Hz).
        band_hz: keep only frequencies ``f1 <= f <= f2`` (Hz).

    Returns:
        (f in Hz, P in unit²/Hz).
    """
    f, P = periodogram(np.asarray(x, dtype=float), fs=fs, window="boxcar", detrend="constant")
    if band_hz is not None:
        f1, f2 = _check_band(band_hz, fs)
        keep = (f >= f1) & (f <= f2)
        f, P = f[keep], P[keep]
    return f, P


def band_rms(x: np.ndarray, fs: float, band_hz: tuple[float, float]) -> float:
    """RMS in a frequency band, ``sqrt(integral of PSD over [f1, f2])`` (thesis Eq 4.9)."""
    f, P = psd(x, fs, band_hz)
    if f.size < 2:
        raise ValueError(f"band {band_hz} Hz holds fewer than 2 frequency bins; record too short")
    return float(np.sqrt(trapezoid(P, f)))


def _check_band(band_hz: tuple[float, float], fs: float) -> tuple[float, float]:
    f1, f2 = (float(b) for b in band_hz)
    if not (0.0 <= f1 < f2):
        raise ValueError(f"frequency band must be 0 <= f1 < f2 Hz, got {band_hz}")
    if f1 > fs / 2:
        raise ValueError(f"band {band_hz} Hz starts above the Nyquist frequency {fs / 2:g} Hz")
    return f1, f2


# ------------------------------------------------------- the thesis's metric (Eq 4.8/4.9)

THESIS_FS = 500.0  # Hz, the rate of the thesis's PSDs (2 ms outputs, App. IV fs = 500)
THESIS_BAND = (0.0, 20.0)  # Hz, Table 4.5 and 5.3; Tables 5.7-5.10 use 0-16 Hz
# Kaiser beta of the anti-aliasing FIR of resample_poly: about -80 dB in the stop band, so the
# switching chatter of an MR run (up to 1 kHz at h = 0.5 ms) does not fold into 0-20 Hz
_AA_KAISER_BETA = 8.0


def resample_to(t: np.ndarray, x: np.ndarray, fs_out: float = THESIS_FS) -> np.ndarray:
    """``x`` sampled at the times ``t`` (s, uniform) resampled to ``fs_out`` (Hz), anti-aliased.

    Polyphase resampling (:func:`scipy.signal.resample_poly`, Kaiser-windowed FIR low-pass
    at the lower Nyquist frequency, zero phase). A record already at ``fs_out`` (a run at
    h = 2 ms for 500 Hz) is returned unchanged (a float copy). Sample ``j`` of the result is
    at ``t[0] + j / fs_out``.

    Raises:
        ValueError: ``t`` not uniform, or the rate ratio not a fraction with denominator
            below 10 000.
    """
    x = np.asarray(x, dtype=float)
    fs_in = sample_rate(t)
    if x.shape != np.shape(t):
        raise ValueError(f"signal has {x.size} samples but the time column {np.size(t)}")
    if abs(fs_in - fs_out) <= 1e-6 * fs_out:
        return x.copy()
    ratio = Fraction(fs_out / fs_in).limit_denominator(10000)
    if abs(float(ratio) - fs_out / fs_in) > 1e-6 * fs_out / fs_in:
        raise ValueError(f"cannot resample {fs_in:g} Hz to {fs_out:g} Hz by a rational ratio")
    return resample_poly(x, ratio.numerator, ratio.denominator,
                         window=("kaiser", _AA_KAISER_BETA))


def matlab_periodogram(x: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """One-sided PSD as MATLAB's ``periodogram(x, [], [], fs)`` (thesis Eq 4.8).

    Rectangular window, no detrending, ``nfft = max(256, 2^nextpow2(N))`` (zero padding),
    density scaling ``|X|^2 / (fs N)`` with the non-DC, non-Nyquist bins doubled.

    Returns:
        (f in Hz, P in unit²/Hz).
    """
    x = np.asarray(x, dtype=float)
    if x.size < 2:
        raise ValueError("need at least 2 samples for a periodogram")
    nfft = max(256, 1 << int(np.ceil(np.log2(x.size))))
    return periodogram(x, fs=fs, window="boxcar", nfft=nfft, detrend=False,
                       return_onesided=True, scaling="density")


def thesis_band_rms(
    t: np.ndarray,
    x: np.ndarray,
    band: tuple[float, float] = THESIS_BAND,
    fs_out: float = THESIS_FS,
) -> float:
    """The thesis's RMS of ``x`` (unit of x) over ``band`` (Hz), whatever the run's step.

    ``x`` at the times ``t`` (s) is resampled anti-aliased to ``fs_out`` (500 Hz,
    :func:`resample_to`), its MATLAB-style periodogram taken (:func:`matlab_periodogram`,
    Eq 4.8), and ``sqrt(trapz(P, f))`` integrated over the bins with ``f1 <= f <= f2``
    (Eq 4.9; the band selected by frequency, not by App. IV's bin indices).
    """
    return periodogram_band_rms(resample_to(t, x, fs_out), fs_out, band)


def periodogram_band_rms(x: np.ndarray, fs: float, band: tuple[float, float]) -> float:
    """``sqrt(trapz)`` of the MATLAB-style periodogram of ``x`` (sampled at ``fs`` Hz) over the
    bins with ``f1 <= f <= f2`` (Hz); unit of x. :func:`thesis_band_rms` without resampling."""
    f, P = matlab_periodogram(x, fs)
    f1, f2 = _check_band(band, fs)
    keep = (f >= f1) & (f <= f2)
    if np.count_nonzero(keep) < 2:
        raise ValueError(f"band {band} Hz holds fewer than 2 frequency bins; record too short")
    return float(np.sqrt(trapezoid(P[keep], f[keep])))


def thesis_wk_rms(t: np.ndarray, a: np.ndarray, fs_out: float = THESIS_FS) -> float:
    """ISO 2631-1 Wk-weighted RMS (m/s²) of the acceleration ``a`` (m/s², at times ``t`` in s)
    after resampling to ``fs_out`` (Hz), as the thesis's band RMS is."""
    return iso2631_wk_weighted_rms(resample_to(t, a, fs_out), fs_out)


def thesis_jerk_rms(t: np.ndarray, a: np.ndarray, fs_out: float = THESIS_FS) -> float:
    """RMS jerk (m/s³) of the acceleration ``a`` (m/s², at times ``t`` in s) by central
    differences on the signal resampled to ``fs_out`` (Hz), so it does not grow with the
    run's own rate (differencing amplifies the high-frequency content of a fine step)."""
    return rms(jerk(resample_to(t, a, fs_out), fs_out))


# --------------------------------------------------------------------- ISO 2631-1 Wk


def wk_response(f_hz: np.ndarray | float) -> np.ndarray:
    """Complex frequency response H(j 2 pi f) of the ISO 2631-1 Wk weighting (-)."""
    s = 2j * np.pi * np.asarray(f_hz, dtype=float)
    w1, w2, w3, w4, w5, w6 = (2 * np.pi * f for f in (WK_F1, WK_F2, WK_F3, WK_F4, WK_F5, WK_F6))
    high = s**2 / (s**2 + w1 * s / WK_Q12 + w1**2)
    low = w2**2 / (s**2 + w2 * s / WK_Q12 + w2**2)
    transition = (1 + s / w3) / (1 + s / (WK_Q4 * w4) + (s / w4) ** 2)
    step = (
        (1 + s / (WK_Q5 * w5) + (s / w5) ** 2)
        / (1 + s / (WK_Q6 * w6) + (s / w6) ** 2)
        * (w5 / w6) ** 2
    )
    return high * low * transition * step


def iso2631_wk(a: np.ndarray, fs: float) -> np.ndarray:
    """Acceleration ``a`` (m/s²) sampled at ``fs`` (Hz) weighted by Wk (m/s²).

    Applied exactly in the frequency domain on a zero-padded FFT (no bilinear warping near
    the Nyquist frequency).
    """
    a = np.asarray(a, dtype=float)
    n = a.size
    nfft = 1 << int(np.ceil(np.log2(max(2 * n, 2))))
    spectrum = np.fft.rfft(a, nfft)
    f = np.fft.rfftfreq(nfft, 1.0 / fs)
    return np.fft.irfft(spectrum * wk_response(f), nfft)[:n]


def iso2631_wk_weighted_rms(a: np.ndarray, fs: float) -> float:
    """Frequency-weighted RMS acceleration a_w (m/s²), ISO 2631-1 Wk (vertical)."""
    return rms(iso2631_wk(a, fs))


# --------------------------------------------------------------- suspension and tyre


def suspension_deflection(z_b: np.ndarray, z_w: np.ndarray) -> np.ndarray:
    """Suspension compression ``z_w - z_b`` (m), positive in bump, from static equilibrium."""
    return np.asarray(z_w, dtype=float) - np.asarray(z_b, dtype=float)


def working_space(z_b: np.ndarray, z_w: np.ndarray) -> float:
    """Suspension working space used (m): max minus min of the deflection ``z_w - z_b``."""
    d = suspension_deflection(z_b, z_w)
    return float(np.max(d) - np.min(d))


def dynamic_tyre_load(F_t: np.ndarray, F_static: float | None = None) -> np.ndarray:
    """Dynamic tyre load ``F_t - F_static`` (N); the static load defaults to the mean of F_t."""
    F_t = np.asarray(F_t, dtype=float)
    return F_t - (float(np.mean(F_t)) if F_static is None else float(F_static))


def jerk(a: np.ndarray, fs: float) -> np.ndarray:
    """Jerk da/dt (m/s³) by central differences (one-sided at the ends)."""
    return np.gradient(np.asarray(a, dtype=float), 1.0 / fs)


# ------------------------------------------------------------------------ run tables


def columns(table: Table, name: str) -> list[tuple[str, np.ndarray]]:
    """The per-corner columns of ``name`` (e.g. ``plant/response/a_b``): ``[(label, array)]``
    with label ``""`` for a scalar field and ``"[i]"`` for list fields; empty if absent."""
    if name in table:
        return [("", np.asarray(table[name], dtype=float))]
    out = []
    i = 0
    while f"{name}[{i}]" in table:
        out.append((f"[{i}]", np.asarray(table[f"{name}[{i}]"], dtype=float)))
        i += 1
    return out


BAND_16 = (0.0, 16.0)  # Hz, the band of thesis Tables 5.7-5.10
ARM_ACCEL_FIELDS = tuple(f"a_arm_{loc}_{ax}" for loc in ("loc1", "cg", "loc2") for ax in "xyz")
"""``plant/response`` fields of the lower arm's point accelerations [m/s^2] (double-wishbone
corner; thesis Table 5.4's Loc1, CG, Loc2 in x, y, z)."""
ROTATION_FIELDS = ("alpha_pitch", "alpha_roll")
"""``plant/response`` fields of the full vehicle's body pitch and roll accelerations
[rad/s^2] (7-DOF model; thesis Tables 5.7-5.10's x and y rows)."""


def metric_values(
    table: Table, band_hz: tuple[float, float] = THESIS_BAND, fs_out: float = THESIS_FS
) -> dict[str, tuple[float, str, str]]:
    """Every ride metric a run table allows, per corner: ``{key: (value, unit, label)}``.

    Keys are stable machine names (``a_b_rms``, ``a_b[2]_rms`` for corner 2 of a full
    vehicle); labels are the text table's row names. Body and wheel accelerations use the
    thesis's metric (:func:`thesis_band_rms`: resampled to ``fs_out``, periodogram, band
    RMS), whatever the run's step:

    * ``a_b_rms``: body RMS over ``band_hz`` (default 0-20 Hz, Table 5.3) -- the headline;
    * ``a_b_rms_0_16``: body RMS over 0-16 Hz (Tables 5.7-5.10);
    * ``a_b_rms_full``: time-domain RMS of the record at the run's own rate (all of its band,
      up to the run's Nyquist frequency; grows with switching chatter at a fine step);
    * ``a_b_wk_rms``: ISO 2631-1 Wk-weighted RMS, ``jerk_b_rms``: RMS jerk, both on the
      ``fs_out`` signal;
    * ``a_w_rms`` / ``a_w_rms_full``: wheel, the same two ways;
    * ``a_arm_<loc>_<ax>_rms``: lower-arm point accelerations (``loc1``, ``cg``, ``loc2``;
      ``x``, ``y``, ``z``; Table 5.4) over ``band_hz``;
    * ``alpha_pitch_rms`` / ``alpha_roll_rms`` (rad/s²): the full vehicle's body pitch and roll
      accelerations over ``band_hz``, and ``..._rms_0_16`` over 0-16 Hz (Tables 5.7-5.10);
    * ``sws`` (mm), ``defl_rms`` (mm), ``dtl_rms`` (N), ``f_d_rms`` (N): suspension working
      space, deflection RMS, dynamic tyre load RMS, damper force RMS, at the run's own rate.

    Uses (when present) ``plant/response/a_b``, ``plant/response/a_w``, the arm-point and
    pitch/roll fields above,
    ``plant/state/z_b``/``z_w``, ``tyre_road/force/F_t`` and ``controller/force/F_d``.
    """
    t = np.asarray(table["t"], dtype=float)
    sample_rate(t)  # a non-uniform time column fails here, with its message
    f1, f2 = (float(b) for b in band_hz)
    m: dict[str, tuple[float, str, str]] = {}
    for lab, a in columns(table, "plant/response/a_b"):
        a5 = resample_to(t, a, fs_out)  # once per signal; every metric below but the full band
        m[f"a_b{lab}_rms"] = (periodogram_band_rms(a5, fs_out, (f1, f2)), "m/s2",
                              f"a_b{lab} RMS {f1:g}-{f2:g} Hz [m/s2]")
        if (f1, f2) != BAND_16:
            m[f"a_b{lab}_rms_0_16"] = (periodogram_band_rms(a5, fs_out, BAND_16), "m/s2",
                                       f"a_b{lab} RMS 0-16 Hz [m/s2]")
        m[f"a_b{lab}_rms_full"] = (rms(a), "m/s2", f"a_b{lab} RMS full band [m/s2]")
        m[f"a_b{lab}_wk_rms"] = (iso2631_wk_weighted_rms(a5, fs_out), "m/s2",
                                 f"a_b{lab} Wk RMS [m/s2]")
        m[f"jerk_b{lab}_rms"] = (rms(jerk(a5, fs_out)), "m/s3", f"jerk_b{lab} RMS [m/s3]")
    for lab, a in columns(table, "plant/response/a_w"):
        m[f"a_w{lab}_rms"] = (thesis_band_rms(t, a, (f1, f2), fs_out), "m/s2",
                              f"a_w{lab} RMS {f1:g}-{f2:g} Hz [m/s2]")
        m[f"a_w{lab}_rms_full"] = (rms(a), "m/s2", f"a_w{lab} RMS full band [m/s2]")
    for name in ARM_ACCEL_FIELDS:
        for lab, a in columns(table, f"plant/response/{name}"):
            m[f"{name}{lab}_rms"] = (thesis_band_rms(t, a, (f1, f2), fs_out), "m/s2",
                                     f"{name}{lab} RMS {f1:g}-{f2:g} Hz [m/s2]")
    for name in ROTATION_FIELDS:
        for lab, a in columns(table, f"plant/response/{name}"):
            a5 = resample_to(t, a, fs_out)
            m[f"{name}{lab}_rms"] = (periodogram_band_rms(a5, fs_out, (f1, f2)), "rad/s2",
                                     f"{name}{lab} RMS {f1:g}-{f2:g} Hz [rad/s2]")
            if (f1, f2) != BAND_16:
                m[f"{name}{lab}_rms_0_16"] = (periodogram_band_rms(a5, fs_out, BAND_16),
                                              "rad/s2", f"{name}{lab} RMS 0-16 Hz [rad/s2]")
    zb, zw = columns(table, "plant/state/z_b"), columns(table, "plant/state/z_w")
    for (lab, b), (_, w) in zip(zb, zw, strict=False):
        m[f"sws{lab}"] = (1e3 * working_space(b, w), "mm", f"SWS{lab} [mm]")
        m[f"defl{lab}_rms"] = (1e3 * rms(suspension_deflection(b, w)), "mm",
                               f"defl{lab} RMS [mm]")
    for lab, F in columns(table, "tyre_road/force/F_t"):
        m[f"dtl{lab}_rms"] = (rms(dynamic_tyre_load(F)), "N", f"DTL{lab} RMS [N]")
    for lab, F in columns(table, "controller/force/F_d"):
        m[f"f_d{lab}_rms"] = (rms(F), "N", f"F_d{lab} RMS [N]")
    return m


def run_metrics(table: Table, band_hz: tuple[float, float] = THESIS_BAND) -> dict[str, float]:
    """Every ride metric a run table allows, per corner, as ``{label: value}`` (the text
    table's row names, units in brackets); see :func:`metric_values` for the definitions."""
    return {label: value for value, _unit, label in metric_values(table, band_hz).values()}


def ride_summary(
    runs: Mapping[str, Table],
    baseline: str | None = None,
    band_hz: tuple[float, float] = THESIS_BAND,
    fs_out: float = THESIS_FS,
) -> dict:
    """Every metric of every run, machine-readable (``suscosim ride --json``).

    Returns:
        ``{"baseline": name, "band_hz": [f1, f2], "fs_metric_hz": fs_out,
        "units": {key: unit}, "labels": {key: label},
        "runs": [{"name", "metrics": {key: value}, "change_pct": {key: %}}]}`` in the order
        of ``runs``; ``change_pct`` (thesis Eq 5.13, positive = reduction) against the
        baseline (default: the first run) for the keys both have; empty for the baseline.
    """
    names, base = _runs_and_baseline(runs, baseline)
    values = {n: metric_values(runs[n], band_hz, fs_out) for n in names}
    units: dict[str, str] = {}
    labels: dict[str, str] = {}
    out_runs = []
    for n in names:
        for key, (_v, unit, label) in values[n].items():
            units.setdefault(key, unit)
            labels.setdefault(key, label)
        metrics = {key: v for key, (v, _u, _l) in values[n].items()}
        change = {} if n == base else {
            key: improvement(values[base][key][0], v)
            for key, v in metrics.items() if key in values[base]}
        out_runs.append({"name": n, "metrics": metrics, "change_pct": change})
    return {"baseline": base, "band_hz": [float(band_hz[0]), float(band_hz[1])],
            "fs_metric_hz": float(fs_out), "units": units, "labels": labels, "runs": out_runs}


def _runs_and_baseline(runs: Mapping[str, Table], baseline: str | None) -> tuple[list[str], str]:
    """The run names in order and the baseline's (default: the first); ValueError if none."""
    if not runs:
        raise ValueError("no runs to compare")
    names = list(runs)
    base = names[0] if baseline is None else baseline
    if base not in runs:
        raise ValueError(f"baseline {base!r} is not one of the runs {names}")
    return names, base


def improvement(baseline: float, value: float) -> float:
    """Thesis Eq 5.13: ``(baseline - value) / baseline * 100`` (%), positive = reduction."""
    return float("nan") if baseline == 0.0 else (baseline - value) / baseline * 100.0


def ride_table(
    runs: Mapping[str, Table],
    baseline: str | None = None,
    band_hz: tuple[float, float] = (0.0, 20.0),
    metrics: Sequence[str] | None = None,
) -> str:
    """Text table comparing runs, laid out like thesis Tables 5.5/5.6: one row per metric, the
    baseline's value, then for every other run its value and the % improvement (Eq 5.13).

    Args:
        runs: run name -> run table (``t`` plus ``<node>/<channel>/<field>`` columns).
        baseline: run the others are compared with (default: the first).
        band_hz: band of the PSD-based RMS (Hz).
        metrics: row names to keep (default: those every run has, in the first run's order).
    """
    names, base = _runs_and_baseline(runs, baseline)
    order = [base] + [n for n in names if n != base]
    values = {n: run_metrics(runs[n], band_hz) for n in order}
    rows = (
        list(metrics)
        if metrics is not None
        else [k for k in values[base] if all(k in values[n] for n in order)]
    )
    header = ["metric", base]
    for n in order[1:]:
        header += [n, "%"]
    body = []
    for key in rows:
        b = values[base].get(key, float("nan"))
        line = [key, f"{b:.4g}"]
        for n in order[1:]:
            v = values[n].get(key, float("nan"))
            line += [f"{v:.4g}", f"{improvement(b, v):.1f}"]
        body.append(line)
    widths = [max(len(r[i]) for r in [header, *body]) for i in range(len(header))]
    fmt = lambda r: "  ".join(  # noqa: E731
        c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(r, widths, strict=True))
    )
    rule = "  ".join("-" * w for w in widths)
    note = (f"% = (({base}) - run) / ({base}) x 100, positive = reduction (thesis Eq 5.13)\n"
            f"band RMS, Wk, jerk: signal resampled to {THESIS_FS:g} Hz, periodogram, "
            f"sqrt(trapz) over the band (thesis Eq 4.8/4.9); full band: the record's own rate")
    return "\n".join([fmt(header), rule, *(fmt(r) for r in body), note])
