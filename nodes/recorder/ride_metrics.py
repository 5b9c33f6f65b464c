"""Ride metrics of a recorded run: RMS, PSD band RMS, ISO 2631-1 Wk weighting, suspension
working space, dynamic tyre load, jerk; and a comparison table of runs (thesis Tables 5.3-5.6).

Pure functions over numpy arrays; ``fs`` in Hz or from a run table's ``t`` column (s);
bands in Hz, never bin indices.

* The thesis's RMS (Eq 4.8/4.9, App. IV; :func:`thesis_band_rms`): resampled anti-aliased
  to 500 Hz (an MR run's chatter above 250 Hz is not counted), MATLAB's default periodogram,
  ``sqrt(trapz)`` over the bins of ``[f1, f2]`` (0-20 Hz; 0-16 Hz for Tables 5.7-5.10).
* ``% improvement`` (thesis Eq 5.13): ``(baseline - run) / baseline * 100``; positive = less.
* ISO 2631-1:1997 Wk (vertical, Annex A Table A.1) by its impulse response (:mod:`.ride_stream`).

One implementation: the estimators of :mod:`.ride_stream`, which read a table in row batches
(a whole table is one batch); tests/unit/ride_oracle.py holds the whole-signal ones they are
checked against.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

Table = Mapping[str, np.ndarray]

# ISO 2631-1:1997 Annex A, Table A.1, weighting Wk
WK_F1, WK_F2 = 0.4, 100.0  # Hz, band limits
WK_Q12 = 1.0 / np.sqrt(2.0)
WK_F3, WK_F4, WK_Q4 = 12.5, 12.5, 0.63  # acceleration-velocity transition
WK_F5, WK_Q5, WK_F6, WK_Q6 = 2.37, 0.91, 3.35, 0.91  # upward step


def sample_rate(t: np.ndarray) -> float:
    """Sampling frequency (Hz) of a uniformly sampled time column ``t`` (s)."""
    from .ride_stream import stream_rate

    return stream_rate([{"t": t}])


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
# Kaiser beta of resample_poly's anti-aliasing FIR: ~-80 dB stop band (MR chatter does not fold)
_AA_KAISER_BETA = 8.0


def resample_to(t: np.ndarray, x: np.ndarray, fs_out: float = THESIS_FS) -> np.ndarray:
    """``x`` at the uniform times ``t`` (s) resampled anti-aliased (polyphase, zero phase, as
    ``scipy.signal.resample_poly``) to ``fs_out`` (Hz); sample ``j`` at ``t[0] + j / fs_out``;
    a copy if already at ``fs_out``. ValueError if ``t`` is not uniform or the ratio needs a
    denominator >= 10 000."""
    from .ride_stream import StreamResampler

    x = np.asarray(x, dtype=float)
    fs_in = sample_rate(t)
    if x.shape != np.shape(t):
        raise ValueError(f"signal has {x.size} samples but the time column {np.size(t)}")
    rs = StreamResampler(x.size, fs_in, fs_out)
    return np.concatenate([rs.add(x), rs.finish()])


def thesis_band_rms(t: np.ndarray, x: np.ndarray, band: tuple[float, float] = THESIS_BAND,
                    fs_out: float = THESIS_FS) -> float:
    """The thesis's RMS (Eq 4.8/4.9) of ``x`` at times ``t`` (s) over ``band`` (Hz), whatever
    the run's step: :func:`resample_to` ``fs_out``, then :func:`periodogram_band_rms`."""
    return periodogram_band_rms(resample_to(t, x, fs_out), fs_out, band)


def periodogram_band_rms(x: np.ndarray, fs: float, band: tuple[float, float]) -> float:
    """``sqrt(trapz)`` of the MATLAB-style periodogram of ``x`` (sampled at ``fs`` Hz: MATLAB's
    ``periodogram(x, [], [], fs)``, rectangular window, no detrend, ``nfft = max(256,
    2^nextpow2(N))``, one-sided density) over the bins with ``f1 <= f <= f2`` (Hz); unit of x.
    :func:`thesis_band_rms` without resampling."""
    from .ride_stream import BandPeriodogram

    x = np.asarray(x, dtype=float)
    pg = BandPeriodogram(x.size, fs, float(band[1]))
    pg.add(x)
    return pg.band_rms(band)


# --------------------------------------------------------------------- ISO 2631-1 Wk


def wk_response(f_hz: np.ndarray | float) -> np.ndarray:
    """Complex frequency response H(j 2 pi f) of the ISO 2631-1 Wk weighting (-)."""
    s = 2j * np.pi * np.asarray(f_hz, dtype=float)
    w1, w2, w3, w4, w5, w6 = (2 * np.pi * f for f in (WK_F1, WK_F2, WK_F3, WK_F4, WK_F5, WK_F6))
    high = s**2 / (s**2 + w1 * s / WK_Q12 + w1**2)
    low = w2**2 / (s**2 + w2 * s / WK_Q12 + w2**2)
    transition = (1 + s / w3) / (1 + s / (WK_Q4 * w4) + (s / w4) ** 2)
    step = ((1 + s / (WK_Q5 * w5) + (s / w5) ** 2) / (1 + s / (WK_Q6 * w6) + (s / w6) ** 2)
            * (w5 / w6) ** 2)
    return high * low * transition * step


def column_names(names: Sequence[str] | Table, name: str) -> list[tuple[str, str]]:
    """The per-corner columns of ``name`` (e.g. ``plant/response/a_b``) among ``names``:
    ``[(label, column)]`` with label ``""`` for a scalar field and ``"[i]"`` for list fields
    (column ``name[i]``); empty if absent."""
    if name in names:
        return [("", name)]
    out: list[tuple[str, str]] = []
    while f"{name}[{len(out)}]" in names:
        out.append((f"[{len(out)}]", f"{name}[{len(out)}]"))
    return out


def columns(table: Table, name: str) -> list[tuple[str, np.ndarray]]:
    """:func:`column_names` of a table with their values, ``[(label, array)]``."""
    return [(lab, np.asarray(table[c], dtype=float)) for lab, c in column_names(table, name)]


BAND_16 = (0.0, 16.0)  # Hz, the band of thesis Tables 5.7-5.10
ARM_ACCEL_FIELDS = tuple(f"a_arm_{loc}_{ax}" for loc in ("loc1", "cg", "loc2") for ax in "xyz")
"""``plant/response`` fields of the lower arm's point accelerations [m/s^2] (double-wishbone
corner; thesis Table 5.4's Loc1, CG, Loc2 in x, y, z)."""
ROTATION_FIELDS = ("alpha_pitch", "alpha_roll")
"""``plant/response`` fields of the full vehicle's body pitch and roll accelerations
[rad/s^2] (7-DOF model; thesis Tables 5.7-5.10's x and y rows)."""


def metric_values(table: Table, band_hz: tuple[float, float] = THESIS_BAND,
                  fs_out: float = THESIS_FS) -> dict[str, tuple[float, str, str]]:
    """Every ride metric a run table allows, per corner: ``{key: (value, unit, label)}``.

    Keys are machine names (``a_b[2]_rms`` for corner 2), labels the text table's rows.
    Accelerations use :func:`thesis_band_rms` (resampled to ``fs_out``):

    * ``a_b_rms``: body over ``band_hz`` (default 0-20 Hz, Table 5.3), the headline;
      ``a_b_rms_0_16`` over 0-16 Hz (Tables 5.7-5.10); ``a_b_rms_full`` time-domain RMS at
      the run's own rate; ``a_b_wk_rms`` ISO 2631-1 Wk RMS; ``jerk_b_rms`` (m/s³);
    * ``a_w_rms`` / ``a_w_rms_full``: wheel, the same two ways;
    * ``a_arm_<loc>_<ax>_rms``: lower-arm points (Table 5.4); ``alpha_pitch_rms`` /
      ``alpha_roll_rms`` (rad/s², and ``_0_16``; Tables 5.7-5.10);
    * ``sws``, ``defl_rms`` (mm), ``dtl_rms``, ``f_d_rms`` (N): working space, deflection,
      dynamic tyre load, damper force, at the run's own rate.
    """
    from .ride_stream import streamed_metric_values

    t = np.asarray(table["t"], dtype=float)
    sample_rate(t)  # a non-uniform time column fails here, with its message
    return streamed_metric_values(
        list(table), t.size, lambda cols: [{c: np.asarray(table[c], dtype=float)
                                            for c in ("t", *cols)}], band_hz, fs_out)


def run_metrics(table: Table, band_hz: tuple[float, float] = THESIS_BAND) -> dict[str, float]:
    """:func:`metric_values` as ``{label: value}`` (units in the labels)."""
    return {label: value for value, _unit, label in metric_values(table, band_hz).values()}


def ride_summary(runs: Mapping[str, Table], baseline: str | None = None,
                 band_hz: tuple[float, float] = THESIS_BAND, fs_out: float = THESIS_FS) -> dict:
    """Every metric of every run (``suscosim ride --json``): ``{"baseline", "band_hz",
    "fs_metric_hz", "units", "labels", "runs": [{"name", "metrics", "change_pct"}]}``;
    ``change_pct`` (Eq 5.13) against the baseline (default: the first run), empty for it."""
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


def ride_table(runs: Mapping[str, Table], baseline: str | None = None,
               band_hz: tuple[float, float] = (0.0, 20.0),
               metrics: Sequence[str] | None = None) -> str:
    """Text table like thesis Tables 5.5/5.6: per metric row (``metrics``, default those
    every run has) the baseline's value (default: first run), then each run's value and %
    improvement (Eq 5.13); ``band_hz`` is the PSD band (Hz)."""
    names, base = _runs_and_baseline(runs, baseline)
    order = [base] + [n for n in names if n != base]
    values = {n: run_metrics(runs[n], band_hz) for n in order}
    rows = list(metrics) if metrics is not None else [
        k for k in values[base] if all(k in values[n] for n in order)]
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
