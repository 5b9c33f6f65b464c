"""The thesis's sinusoidal tests of the control laws (Sec 5.5.1, Figs 5.11-5.17), pure numerics.

The thesis ran them "in MATLAB/Simulink" on the lumped 2-DOF QVM of Table 4.3 (m_b = 535 kg,
m_w = 47.75 kg, k_s = 31 kN/m, k_t = 239 kN/m), road z_g = A sin(2 pi f t) with A = 10 mm and
f = 1, 1.5, 5, 10, 12, 15 Hz (1-15 Hz for the RMS curves), passive 1500 N s/m against TSS1,
TSS2 and TSS3. This module does the same with this package's own controllers (built from a
``[controller]`` table by :func:`nodes.controller.laws.build_controller`, so the MR damper
and the laws are exactly those of a co-simulation run) and a 2-DOF quarter car integrated here
(no PyBullet: the controller package may not import the plant, and the thesis's study was a
pure Simulink one):

    m_b z_b'' = -k_s (z_b - z_w) + F_d
    m_w z_w'' =  k_s (z_b - z_w) - F_d + max(-W, k_t (z_g - z_w))   (deviations; lift-off)

with F_d the damper force on the body (up positive, :mod:`nodes.controller.base`), W the
static tyre load (m_b + m_w) g. Each communication step h the controller is asked for F_d at
t_k and its slope c_eff; between steps the force is F_d + c_eff (v_rel - v_rel,k) (the
Jacobian coupling of the co-simulation), integrated by classical RK4 in ``substeps``.

The thesis's figures carry no digitised data: what can be compared is in
``tests/controller/data/thesis_ch5_sine.csv`` (the axis ranges of each panel, with where each
number came from) and ``docs/control.md`` / ``docs/ch5_control_comparison.md``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .laws import build_controller

GRAVITY = 9.81  # m/s^2

#: The thesis's laws on the lumped QVM (Table 5.2 lumped pair; the MR damper scaled by the
#: lumped model's motion ratio 0.628, as in scenarios/ch5_qvm_tss{2,3}_random.toml).
THESIS_LAWS: dict[str, dict[str, Any]] = {
    "passive": {"law": "passive", "c": 1500.0},
    "tss1": {"law": "tss1", "preset": "lumped"},
    "tss2": {"law": "tss2", "preset": "lumped", "damper": {"motion_ratio": 0.628}},
    "tss3": {"law": "tss3", "I_soft": 0.0, "I_hard": 0.6, "damper": {"motion_ratio": 0.628}},
}
#: The frequencies of Figs 5.11-5.15 (Hz).
THESIS_FREQUENCIES = (1.0, 1.5, 5.0, 10.0, 12.0, 15.0)


@dataclass(frozen=True)
class QuarterCar:
    """Lumped 2-DOF QVM, Table 4.3 (SI units)."""

    m_b: float = 535.0
    m_w: float = 47.75
    k_s: float = 31000.0
    k_t: float = 239000.0


def sine_response(law: Mapping[str, Any], freqs: Sequence[float], *, amplitude: float = 0.01,
                  h: float = 5e-4, substeps: int = 4, t_end: float | None = None,
                  car: QuarterCar = QuarterCar()) -> dict[str, np.ndarray]:
    """Quarter cars on z_g = amplitude [m] sin(2 pi f t), one per frequency [Hz], from rest,
    as the independent "corners" of one controller built from the ``[controller]`` table
    ``law``; ``h`` [s] (the MR laws need 0.5 ms, Sec 5.3.3); ``t_end`` default 6 s (the body
    transient, 1/(zeta omega) = 0.7 s, decayed to 0.02 %) plus 3 periods of the lowest f.

    Returns histories of shape (steps + 1, len(freqs)): ``z_g``, ``z_b``, ``z_w`` [m],
    ``v_rel`` [m/s], ``F_d`` [N, on the body], ``a_b``, ``a_w`` [m/s^2], ``I`` [A, NaN
    without current]; ``t`` [s] of shape (steps + 1,)."""
    f = np.asarray(freqs, dtype=float).reshape(-1)
    if f.size == 0 or np.any(f <= 0) or amplitude <= 0 or h <= 0:
        raise ValueError(f"freqs, amplitude and h must be > 0, got {freqs}, {amplitude}, {h}")
    m = f.size
    ctrl = build_controller(dict(law), m, h)
    T = 6.0 + 3.0 / float(f.min()) if t_end is None else t_end
    n = int(round(T / h))
    w = 2 * np.pi * f
    W = (car.m_b + car.m_w) * GRAVITY
    y = np.zeros((4, m))  # z_b, v_b, z_w, v_w

    def rhs(t: float, y: np.ndarray, F0: np.ndarray, c: np.ndarray,
            vr0: np.ndarray) -> np.ndarray:
        z_b, v_b, z_w, v_w = y
        F_d = F0 + c * ((v_w - v_b) - vr0)
        F_s = car.k_s * (z_w - z_b)
        F_t = np.maximum(-W, car.k_t * (amplitude * np.sin(w * t) - z_w))
        return np.array([v_b, (F_s + F_d) / car.m_b, v_w, (F_t - F_s - F_d) / car.m_w])

    keys = ("z_g", "z_b", "z_w", "v_rel", "F_d", "a_b", "a_w", "I")
    out = {k: np.empty((n + 1, m)) for k in keys}
    out["t"] = np.arange(n + 1) * h  # type: ignore[assignment]  # 1-D, the others 2-D
    dt = h / substeps
    try:
        for k in range(n + 1):
            t = k * h
            co = ctrl.step(t, {"z_b": y[0], "v_b": y[1], "z_w": y[2], "v_w": y[3]})
            F0, c = np.asarray(co.F_d, dtype=float), np.asarray(co.c_eff, dtype=float)
            vr0 = y[3] - y[1]
            acc = rhs(t, y, F0, c, vr0)
            out["z_g"][k] = amplitude * np.sin(w * t)
            out["z_b"][k], out["z_w"][k], out["v_rel"][k] = y[0], y[2], vr0
            out["F_d"][k], out["a_b"][k], out["a_w"][k] = F0, acc[1], acc[3]
            out["I"][k] = co.extra["I"] if "I" in co.extra else np.nan
            if k == n:
                break
            for j in range(substeps):
                s = t + j * dt
                k1 = rhs(s, y, F0, c, vr0)
                k2 = rhs(s + dt / 2, y + dt / 2 * k1, F0, c, vr0)
                k3 = rhs(s + dt / 2, y + dt / 2 * k2, F0, c, vr0)
                k4 = rhs(s + dt, y + dt * k3, F0, c, vr0)
                y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    finally:
        ctrl.close()
    return out


def steady(r: Mapping[str, np.ndarray], freqs: Sequence[float], i: int,
           periods: float = 2.0) -> dict[str, np.ndarray]:
    """Frequency ``i``'s last ``periods`` periods of a :func:`sine_response` record."""
    t = r["t"]
    keep = t >= t[-1] - periods / float(freqs[i])
    return {k: (v[keep] if k == "t" else v[keep, i]) for k, v in r.items()}


def rms(x: np.ndarray) -> float:
    """Root mean square of a steady record [its unit]."""
    return float(np.sqrt(np.mean(np.square(x))))
