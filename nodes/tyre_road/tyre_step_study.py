"""Fixed footprint against point contact on the Ch. 3 step (thesis Sec. 3.5.3, Fig. 3.19).

The Ch. 3 lumped quarter car (Table 3.1: M_b 317.5 kg, M_w 45.4 kg, k_s 22 000 N/m,
c_s 1500 N s/m, k_t 192 000 N/m), Eq. 3.1 with a passive damper, over a 20 mm step reached at
t = 0.5 s, integrated by fixed-step RK4 (0.05 ms) with the PC or the FFP tyre of
:mod:`nodes.tyre_road.tyres`. The thesis gives no contact length or speed for the FFP; we use
n = 4 springs over l_c = 0.20 m (a typical loaded passenger-car footprint) at 47 km/h (the
speed of the thesis's tyre paper, App. I), i.e. 5.1 ms between springs.

Run: ``python -m orchestrator.studies.tyre_step [--speed-kmh 47] [--contact-length 0.2]``.
"""

from __future__ import annotations

import numpy as np

from .roads import step_height
from .tyres import FixedFootprint, PointContact, Tyre

M_B, M_W, K_S, C_S, K_T, G = 317.5, 45.4, 22000.0, 1500.0, 192000.0, 9.81


def step_response(tyre: Tyre, speed: float, height: float = 0.02, t_step: float = 0.5,
                  t_end: float = 1.5, dt: float = 5e-5) -> dict[str, np.ndarray]:
    """Time histories t, F_t, z_b, z_w of the Ch. 3 quarter car over the step."""
    W = (M_B + M_W) * G
    x_step = speed * t_step  # the wheel centre reaches the step at t_step

    def deriv(t: float, y: np.ndarray) -> tuple[np.ndarray, float]:
        zb, vb, zw, vw = y
        z_g = step_height(speed * t + tyre.contact_offsets, x_step, height)
        F_t, _ = tyre.force(np.array(zw), z_g, np.array(W))
        F_s = K_S * (zw - zb) + C_S * (vw - vb)
        return np.array([vb, F_s / M_B, vw, (float(F_t) - W - F_s) / M_W]), float(F_t)

    n = int(round(t_end / dt))
    y = np.zeros(4)
    out = np.empty((n, 4))
    for k in range(n):
        t = k * dt
        k1, F = deriv(t, y)
        k2, _ = deriv(t + dt / 2, y + dt / 2 * k1)
        k3, _ = deriv(t + dt / 2, y + dt / 2 * k2)
        k4, _ = deriv(t + dt, y + dt * k3)
        out[k] = (t, F, y[0], y[2])
        y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return {"t": out[:, 0], "F_t": out[:, 1], "z_b": out[:, 2], "z_w": out[:, 3]}


def compare(speed_kmh: float = 47.0, contact_length: float = 0.2, n: int = 4
            ) -> dict[str, float]:
    """PC vs FFP peaks: tyre force, wheel and body displacement, and the FFP lag."""
    v = speed_kmh / 3.6
    pc = step_response(PointContact(K_T), v)
    ffp = step_response(FixedFootprint(n, contact_length, K_T), v)
    i_pc, i_ffp = np.argmax(pc["F_t"]), np.argmax(ffp["F_t"])
    return {
        "F_pc": float(pc["F_t"][i_pc]), "F_ffp": float(ffp["F_t"][i_ffp]),
        "F_diff_pct": 100 * float(pc["F_t"][i_pc] / ffp["F_t"][i_ffp] - 1),
        "lag_ms": 1e3 * float(ffp["t"][i_ffp] - pc["t"][i_pc]),
        "z_w_diff_pct": 100 * float(pc["z_w"].max() / ffp["z_w"].max() - 1),
        "z_b_diff_pct": 100 * float(pc["z_b"].max() / ffp["z_b"].max() - 1),
        "spring_delay_ms": 1e3 * contact_length / max(n - 1, 1) / v,
    }
