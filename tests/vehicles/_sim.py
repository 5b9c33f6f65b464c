"""A tiny closed loop for tests: a plant model with a passive damper and point-contact tyres
(what the controller and tyre/road nodes do), stepped in one Python loop."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


def run_closed_loop(model, t_end: float, dt: float, k_t: float, c_s: float,
                    z_g: Callable[[float], np.ndarray]) -> dict[str, np.ndarray]:
    """Return time histories of the state keys and the tyre force ``F_t``."""
    W = model.static_tyre_load()
    out: dict[str, list] = {"t": [], "F_t": []}
    n = int(round(t_end / dt))
    for k in range(n):
        t = k * dt
        st = model.state()
        F_t = np.maximum(0.0, W + k_t * (z_g(t) - st["z_w"]))
        F_d = c_s * (st["v_w"] - st["v_b"])
        model.substep(dt, F_t, F_d)
        st = model.state()
        out["t"].append(t + dt)
        out["F_t"].append(F_t)
        for key, v in st.items():
            out.setdefault(key, []).append(np.array(v, dtype=float))
    return {k: np.array(v) for k, v in out.items()}


def peak_frequency(x: np.ndarray, dt: float, f_lo: float, f_hi: float) -> float:
    """Frequency [Hz] of the largest spectral peak of ``x`` in [f_lo, f_hi] (Hann window,
    zero padding x8, parabolic interpolation on the log magnitude)."""
    x = np.asarray(x, dtype=float) - np.mean(x)
    n = 8 * len(x)
    X = np.abs(np.fft.rfft(x * np.hanning(len(x)), n=n))
    f = np.fft.rfftfreq(n, dt)
    band = np.where((f >= f_lo) & (f <= f_hi))[0]
    i = band[np.argmax(X[band])]
    a, b, c = np.log(X[i - 1:i + 2])
    return float(f[i] + 0.5 * (a - c) / (a - 2 * b + c) * (f[1] - f[0]))
