"""Closed-form bounds behind the Figs 5.11-5.15 points our MR model misses (issue #27 item 2).

The lumped 2-DOF QVM of Table 4.3 (nodes.controller.sine_study.QuarterCar) on z_g = A sin(wt),
A = 10 mm, with a *linear* damper c [N s/m], has the steady relative velocity and wheel
acceleration amplitudes

    [ -m_b w^2 + k_s + i w c,   -(k_s + i w c)              ] [Z_b]   [  0    ]
    [ -(k_s + i w c),   -m_w w^2 + k_s + k_t + i w c        ] [Z_w] = [ k_t A ]

|v_rel| = w |Z_b - Z_w|, |a_w| = w^2 |Z_w|. The laws switch c between bounds (passive 1500;
TSS1 lumped 1500 / 2368); the switched response lies between the linear ones in practice (the
simulated values are printed beside). The MR force on the wheel is bounded by the static
bi-viscous law through the motion ratio r: |F| <= r (F_y(I) + c_post(I) r |v_rel|) (the series
K_f / M_f element resonates at 148 Hz: no amplification at 1-5 Hz).

    python bench/ch5_sine_bounds.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from nodes.controller import mr_damper as mr  # noqa: E402
from nodes.controller.sine_study import QuarterCar  # noqa: E402

A = 0.01  # m, road sine amplitude (Sec 5.5.1)


CAR = QuarterCar()


def linear_amplitudes(f: float, c: float, car: QuarterCar = CAR) -> tuple[float, float]:
    """Steady (|v_rel| [m/s], |a_w| [m/s^2]) of the linear 2-DOF at f [Hz] with damper c."""
    w = 2.0 * np.pi * f
    ks = car.k_s + 1j * w * c
    M = np.array([[-car.m_b * w**2 + ks, -ks], [-ks, -car.m_w * w**2 + ks + car.k_t]])
    zb, zw = np.linalg.solve(M, np.array([0.0, car.k_t * A]))
    return float(w * abs(zb - zw)), float(w**2 * abs(zw))


def main() -> int:
    p = mr.MRParams()
    print("| f [Hz] | c [N s/m] | |v_rel| [m/s] | |a_w| [m/s^2] |\n|---|---|---|---|")
    for f in (1.0, 1.5, 5.0):
        for c in (0.0, 1500.0, 2368.0, 3800.0, 6000.0):
            v, a = linear_amplitudes(f, c)
            print(f"| {f:g} | {c:g} | {v:.3f} | {a:.2f} |")
    fy, cp = float(mr.yield_force(0.6, p)), float(mr.c_post(0.6, p))
    print(f"\nMR force bound |F| <= r (F_y + c_post r v), I = 0.6 A (F_y {fy:.0f} N, "
          f"c_post {cp:.0f} N s/m):")
    for f in (1.0, 5.0):
        vmax = max(linear_amplitudes(f, c)[0] for c in np.linspace(0.0, 6000.0, 61))
        for r in (0.628, 1.0):
            bound = r * (fy + cp * r * vmax)
            print(f"  f = {f:g} Hz, max linear |v_rel| over c in 0-6000 = {vmax:.3f} m/s, "
                  f"r = {r:g}: |F| <= {bound:.0f} N")
    return 0


if __name__ == "__main__":
    sys.exit(main())
