"""The ride metrics' estimators (:func:`.ride_metrics.metric_values`), fed a run's table in
row batches: memory does not grow with whole columns. Each is compared with the whole-signal
one of ``tests/unit/ride_oracle.py`` by ``tests/unit/test_ride_stream.py``:

* **Resampling to 500 Hz** (:class:`StreamResampler`): ``resample_poly``'s own FIR, padding
  and trimming, applied by ``upfirdn`` to windows holding each output's support: bit for bit.
* **Band RMS** (Eq 4.8/4.9, :class:`BandPeriodogram`): the same whole-record MATLAB-style
  periodogram (``N`` known from the row count), only the bins up to the band's top:
  ``X_k = sum over segments of e^{-2 pi i k n0 / nfft} DFT_segment(k)``, each by a Bluestein
  chirp-z with integer-reduced phases (to 1e-12). Memory ``16 B x nfft x f2 / fs`` per
  signal; a Welch average would be bounded but moves the Chapter 5 values.
* **ISO 2631-1 Wk** (:class:`StreamWk`): overlap-save with the impulse response of H
  (:func:`.ride_metrics.wk_response`) on the grid of a zero-padded FFT of the whole signal
  when it is at most :data:`WK_GRID` points (to 1e-13); longer records use H on
  :data:`WK_GRID` points cut to +-:data:`WK_HALF` lags (65.5 s at 500 Hz; 2.5e-8 at 500 s,
  tested to 1e-7).
* **Jerk**: ``np.gradient``'s differences (bit for bit). **RMS**: batch sums of squares (to
  1e-12). **SWS**: max - min. **DTL**: Chan's combination of batch moments (to 1e-12).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from fractions import Fraction
from functools import partial

import numpy as np
from scipy.fft import next_fast_len
from scipy.integrate import trapezoid
from scipy.signal import fftconvolve, firwin, upfirdn

from . import ride_metrics as rm

WK_GRID = 1 << 17
"""Points of the frequency grid the streamed Wk filter's impulse response is taken from."""
WK_HALF = 1 << 15
"""Lags each side of the streamed Wk filter's impulse response [samples] (65.5 s at 500 Hz)."""
SEGMENT = 1 << 14
"""Longest segment of a :class:`BandPeriodogram` DFT [samples] (bounds its workspace)."""

Batches = Callable[[Sequence[str]], Iterable[dict[str, np.ndarray]]]
"""``batches(columns)``: the table's ``{column: values}`` a batch at a time (``t`` always)."""


def _output_len(len_h: int, n_in: int, up: int, down: int) -> int:
    """Samples ``upfirdn`` returns (scipy's private ``_upfirdn._output_len``)."""
    return ((n_in - 1) * up + len_h - 1) // down + 1


_NOT_UNIFORM = "time column is not uniformly sampled (a run with missing steps?)"


def stream_rate(batches: Iterable[dict[str, np.ndarray]]) -> float:
    """:func:`.ride_metrics.sample_rate` [Hz] of a ``t`` column [s] read in batches."""
    step: float | None = None
    last: np.ndarray | None = None
    n = 0
    for b in batches:
        t = np.asarray(b["t"], dtype=float)
        n += t.size
        tt = t if last is None else np.r_[last, t]
        if tt.size < 2:
            last = tt if tt.size else last
            continue
        dt = np.diff(tt)
        if step is None:
            step = float(np.median(dt))
            if step <= 0.0:
                raise ValueError(_NOT_UNIFORM)
        if np.max(np.abs(dt - step)) > 0.01 * step:
            raise ValueError(_NOT_UNIFORM)
        last = tt[-1:]
    if step is None or n < 2:
        raise ValueError("need at least 2 samples to know the sampling rate")
    return 1.0 / step


class StreamResampler:
    """:func:`.ride_metrics.resample_to` of ``n_in`` samples at ``fs_in`` [Hz] fed in pieces:
    :meth:`add` and :meth:`finish` return the output samples now complete, in order."""

    def __init__(self, n_in: int, fs_in: float, fs_out: float = rm.THESIS_FS) -> None:
        self.identity = abs(fs_in - fs_out) <= 1e-6 * fs_out
        self.n_out = n_in
        if self.identity:
            return
        ratio = Fraction(fs_out / fs_in).limit_denominator(10000)
        if abs(float(ratio) - fs_out / fs_in) > 1e-6 * fs_out / fs_in:
            raise ValueError(f"cannot resample {fs_in:g} Hz to {fs_out:g} Hz by a rational ratio")
        up, down = ratio.numerator, ratio.denominator
        if up == down == 1:
            self.identity = True
            return
        # scipy.signal.resample_poly's filter, padding and trimming (scipy 1.17)
        max_rate = max(up, down)
        half_len = 10 * max_rate
        h = firwin(2 * half_len + 1, 1.0 / max_rate, window=("kaiser", rm._AA_KAISER_BETA)) * up
        n_pre_pad = down - half_len % down
        n_post_pad = 0
        self.n_out = n_in * up // down + bool(n_in * up % down)
        self.pre_remove = (half_len + n_pre_pad) // down
        while (_output_len(h.shape[0] + n_pre_pad + n_post_pad, n_in, up, down)
               < self.n_out + self.pre_remove):
            n_post_pad += 1
        self.h = np.concatenate((np.zeros(n_pre_pad), h, np.zeros(n_post_pad)))
        self.up, self.down = up, down
        self.m_end = self.pre_remove + self.n_out
        self.m_next = 0
        self.s = 0  # input index of buf[0], a multiple of down
        self.buf = np.zeros(0)

    def add(self, x: np.ndarray) -> np.ndarray:
        """Feed the next input samples; the output samples now complete."""
        x = np.asarray(x, dtype=float)
        if self.identity:
            return x.copy()
        self.buf = np.concatenate([self.buf, x])
        e = self.s + self.buf.size
        return self._emit(min((e * self.up - 1) // self.down, self.m_end - 1))

    def finish(self) -> np.ndarray:
        """The last output samples (the input ended: zeros beyond it, as resample_poly)."""
        return np.zeros(0) if self.identity else self._emit(self.m_end - 1)

    def _emit(self, m_hi: int) -> np.ndarray:
        if m_hi < self.m_next:
            return np.zeros(0)
        y = upfirdn(self.h, self.buf, self.up, self.down)
        off = self.s * self.up // self.down
        lo, hi = self.m_next - off, m_hi - off + 1
        out = y[lo:hi]
        if out.size < hi - lo:
            out = np.concatenate([out, np.zeros(hi - lo - out.size)])
        first = self.m_next
        self.m_next = m_hi + 1
        need = -(-(self.m_next * self.down - self.h.size + 1) // self.up)
        s_new = max(self.s, max(0, need) // self.down * self.down)
        self.buf, self.s = self.buf[s_new - self.s:], s_new
        return out[max(0, self.pre_remove - first):]


def _chirp(j: np.ndarray, nfft: int) -> np.ndarray:
    """``e^{-i pi j^2 / nfft}`` with ``j^2`` reduced modulo ``2 nfft`` in integers."""
    j = np.asarray(j, dtype=np.int64)
    return np.exp(-1j * np.pi * ((j * j) % (2 * nfft)) / nfft)


class BandPeriodogram:
    """Bins up to ``f_max`` [Hz] of :func:`.ride_metrics.matlab_periodogram` of ``n``
    samples at ``fs`` [Hz] fed in pieces."""

    def __init__(self, n: int, fs: float, f_max: float) -> None:
        if n < 2:
            raise ValueError("need at least 2 samples for a periodogram")
        self.n, self.fs = n, fs
        self.nfft = max(256, 1 << int(np.ceil(np.log2(n))))
        val = 1.0 / (self.nfft * (1.0 / fs))  # scipy.fft.rfftfreq's bin width
        k_top = min(self.nfft // 2, int(np.floor(f_max / val)) + 1)
        self.f = np.arange(k_top + 1) * val
        self.X = np.zeros(k_top + 1, dtype=complex)
        self.pos = 0

    def add(self, x: np.ndarray) -> None:
        """Feed the next samples [unit]."""
        x = np.asarray(x, dtype=float)
        for i in range(0, x.size, SEGMENT):
            self._segment(x[i:i + SEGMENT])

    def _segment(self, seg: np.ndarray) -> None:
        B, K, nfft = seg.size, self.X.size, self.nfft
        if B == 0:
            return
        if self.pos + B > self.n:
            raise ValueError(f"more than the {self.n} samples announced")
        k = np.arange(K)
        # Bluestein: X_k = c_k sum_b (x_b c_b) conj(c_{k-b}), c_j = e^{-i pi j^2 / nfft}
        M = next_fast_len(B + K - 1)
        v = np.zeros(M, dtype=complex)
        v[:K] = np.conj(_chirp(k, nfft))
        if B > 1:
            v[M - (B - 1):] = np.conj(_chirp(np.arange(-(B - 1), 0), nfft))
        u = seg * _chirp(np.arange(B), nfft)
        conv = np.fft.ifft(np.fft.fft(u, M) * np.fft.fft(v))[:K]
        shift = np.exp(-2j * np.pi * ((k.astype(np.int64) * self.pos) % nfft) / nfft)
        self.X += shift * _chirp(k, nfft) * conv
        self.pos += B

    def band_rms(self, band: tuple[float, float]) -> float:
        """:func:`.ride_metrics.periodogram_band_rms` [unit]."""
        if self.pos != self.n:
            raise ValueError(f"{self.pos} samples fed of the {self.n} announced")
        f1, f2 = rm._check_band(band, self.fs)
        P = (self.X.real ** 2 + self.X.imag ** 2) / (self.fs * self.n)
        k = np.arange(P.size)
        P[(k >= 1) & (k < self.nfft // 2)] *= 2.0
        keep = (self.f >= f1) & (self.f <= f2)
        if np.count_nonzero(keep) < 2:
            raise ValueError(f"band {band} Hz holds fewer than 2 frequency bins; record too short")
        return float(np.sqrt(trapezoid(P[keep], self.f[keep])))


class StreamWk:
    """Sum of squares of :func:`.ride_metrics.iso2631_wk` of ``n`` samples at ``fs`` [Hz]
    fed in pieces (overlap-save)."""

    def __init__(self, n: int, fs: float) -> None:
        nfft = 1 << int(np.ceil(np.log2(max(2 * n, 2))))  # iso2631_wk's grid
        grid, self.half = (nfft, nfft // 2) if nfft <= WK_GRID else (WK_GRID, WK_HALF)
        h = np.fft.irfft(rm.wk_response(np.fft.rfftfreq(grid, 1.0 / fs)), grid)
        self.taps = np.concatenate([h[-self.half:], h[:self.half + 1]])  # lags -half..half
        self.n = n
        self.held = np.zeros(self.half)  # the zeros before the signal, then its last 2 half
        self.done = 0
        self.sumsq = 0.0

    def add(self, x: np.ndarray) -> None:
        """Feed the next samples [m/s^2]."""
        buf = np.concatenate([self.held, np.asarray(x, dtype=float)])
        if buf.size < 2 * self.half + 1:
            self.held = buf
            return
        y = fftconvolve(buf, self.taps, mode="valid")[: self.n - self.done]
        self.sumsq += float(np.sum(y * y))
        self.done += y.size
        self.held = buf[buf.size - 2 * self.half:]

    def rms(self) -> float:
        """The Wk-weighted RMS [m/s^2] (after every sample was fed)."""
        self.add(np.zeros(self.half))  # the zeros after the signal
        if self.done != self.n:
            raise ValueError(f"Wk filter: {self.done} of {self.n} samples")
        return float(np.sqrt(self.sumsq / self.n))


class StreamJerk:
    """Sum of squares of :func:`.ride_metrics.jerk` of a signal fed in pieces."""

    def __init__(self, fs: float) -> None:
        self.dx = 1.0 / fs
        self.held = np.zeros(0)
        self.n = 0
        self.sumsq = 0.0

    def add(self, a: np.ndarray) -> None:
        """Feed the next samples [m/s^2]."""
        a = np.asarray(a, dtype=float)
        buf = np.concatenate([self.held, a])
        if self.n < 2 <= self.n + a.size:
            j0 = (buf[1] - buf[0]) / self.dx
            self.sumsq += float(j0 * j0)
        if buf.size >= 3:
            j = (buf[2:] - buf[:-2]) / (2.0 * self.dx)
            self.sumsq += float(np.sum(j * j))
        self.n += a.size
        self.held = buf[-2:]

    def rms(self) -> float:
        """RMS jerk [m/s^3] (after every sample was fed)."""
        if self.n < 2:
            raise ValueError("jerk of fewer than 2 samples")
        j1 = (self.held[-1] - self.held[-2]) / self.dx
        return float(np.sqrt((self.sumsq + float(j1 * j1)) / self.n))


class Moments:
    """Count, sum of squares, extremes, mean, centred sum of squares (Chan et al. 1979)."""

    def __init__(self) -> None:
        self.n, self.sumsq, self.mean, self.m2 = 0, 0.0, 0.0, 0.0
        self.lo, self.hi = np.inf, -np.inf

    def add(self, x: np.ndarray) -> None:
        """Feed the next samples."""
        x = np.asarray(x, dtype=float)
        if x.size == 0:
            return
        self.sumsq += float(np.sum(x * x))
        self.lo, self.hi = min(self.lo, float(np.min(x))), max(self.hi, float(np.max(x)))
        mb = float(np.mean(x))
        m2b = float(np.sum((x - mb) ** 2))
        n = self.n + x.size
        delta = mb - self.mean
        self.m2 += m2b + delta * delta * self.n * x.size / n
        self.mean = mb if self.n == 0 else self.mean + delta * x.size / n
        self.n = n

    def rms(self) -> float:
        """Root mean square [unit]."""
        if self.n == 0:
            raise ValueError("rms of an empty signal")
        return float(np.sqrt(self.sumsq / self.n))

    def centred_rms(self) -> float:
        """RMS about the mean [unit] (the dynamic tyre load's)."""
        if self.n == 0:
            raise ValueError("rms of an empty signal")
        return float(np.sqrt(self.m2 / self.n))


class _Band:
    """A signal's resampler and in-band periodogram (and, for the body, Wk and jerk)."""

    def __init__(self, n: int, fs_in: float, fs_out: float, f_max: float, body: bool) -> None:
        self.rs = StreamResampler(n, fs_in, fs_out)
        self.pg = BandPeriodogram(self.rs.n_out, fs_out, f_max)
        self.wk = StreamWk(self.rs.n_out, fs_out) if body else None
        self.jerk = StreamJerk(fs_out) if body else None
        self.raw = Moments()

    def add(self, x: np.ndarray, last: bool = False) -> None:
        self.raw.add(x)
        y = self.rs.add(x)
        if last:
            y = np.concatenate([y, self.rs.finish()])
        self.pg.add(y)
        if self.wk is not None and self.jerk is not None:
            self.wk.add(y)
            self.jerk.add(y)


_R = "plant/response/"
#: The band-RMS signals: (column base, unit, full-band RMS, Wk and jerk, 0-16 Hz band).
_BANDED = (("a_b", "m/s2", True, True, True), ("a_w", "m/s2", True, False, False),
           *((f, "m/s2", False, False, False) for f in rm.ARM_ACCEL_FIELDS),
           *((f, "rad/s2", False, False, True) for f in rm.ROTATION_FIELDS))


def streamed_metric_values(
    names: Sequence[str], n_rows: int, batches: Batches,
    band_hz: tuple[float, float] = rm.THESIS_BAND, fs_out: float = rm.THESIS_FS,
) -> dict[str, tuple[float, str, str]]:
    """:func:`.ride_metrics.metric_values` (its keys, units and labels) of a table of
    ``n_rows`` rows and columns ``names`` read by ``batches`` (two passes: ``t``, then the
    ride columns)."""
    series = partial(rm.column_names, names)
    bases = (*(f"{_R}{b[0]}" for b in _BANDED), "plant/state/z_b", "tyre_road/force/F_t",
             "controller/force/F_d")
    if not any(series(b) for b in bases):
        return {}  # no ride channel: nothing to compute (and no rate needed)
    fs = stream_rate(batches(["t"]))
    f1, f2 = (float(b) for b in band_hz)
    band: dict[str, _Band] = {col: _Band(n_rows, fs, fs_out, max(f2, rm.BAND_16[1]), b[3])
                              for b in _BANDED for _lab, col in series(f"{_R}{b[0]}")}
    zb, zw = series("plant/state/z_b"), series("plant/state/z_w")
    pairs = list(zip(zb, zw, strict=False))
    defl = {cb: Moments() for (_l, cb), _w in pairs}
    plain = {col: Moments() for base in ("tyre_road/force/F_t", "controller/force/F_d")
             for _l, col in series(base)}
    seen = 0
    for b in batches([*band, *(c for p in pairs for _l, c in p), *plain]):
        seen += b["t"].size
        for col, sig in band.items():
            sig.add(b[col], seen >= n_rows)
        for (_l, cb), (_l2, cw) in pairs:
            defl[cb].add(np.asarray(b[cw], dtype=float) - b[cb])  # compression z_w - z_b
        for col, mo in plain.items():
            mo.add(b[col])
    if seen != n_rows:
        raise ValueError(f"the table gave {seen} rows of the {n_rows} announced")

    m: dict[str, tuple[float, str, str]] = {}
    for name, unit, full, _body, b16 in _BANDED:
        for lab, col in series(f"{_R}{name}"):
            s, key, u = band[col], f"{name}{lab}", f"[{unit}]"
            m[f"{key}_rms"] = (s.pg.band_rms((f1, f2)), unit, f"{key} RMS {f1:g}-{f2:g} Hz {u}")
            if b16 and (f1, f2) != rm.BAND_16:
                m[f"{key}_rms_0_16"] = (s.pg.band_rms(rm.BAND_16), unit, f"{key} RMS 0-16 Hz {u}")
            if full:
                m[f"{key}_rms_full"] = (s.raw.rms(), unit, f"{key} RMS full band {u}")
            if s.wk is not None and s.jerk is not None:
                m[f"{key}_wk_rms"] = (s.wk.rms(), unit, f"{key} Wk RMS {u}")
                m[f"jerk_b{lab}_rms"] = (s.jerk.rms(), "m/s3", f"jerk_b{lab} RMS [m/s3]")
    for (lab, cb), _w in pairs:
        d = defl[cb]
        m[f"sws{lab}"] = (1e3 * (d.hi - d.lo), "mm", f"SWS{lab} [mm]")
        m[f"defl{lab}_rms"] = (1e3 * d.rms(), "mm", f"defl{lab} RMS [mm]")
    for lab, col in series("tyre_road/force/F_t"):
        m[f"dtl{lab}_rms"] = (plain[col].centred_rms(), "N", f"DTL{lab} RMS [N]")
    for lab, col in series("controller/force/F_d"):
        m[f"f_d{lab}_rms"] = (plain[col].rms(), "N", f"F_d{lab} RMS [N]")
    return m

