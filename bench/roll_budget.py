"""Where the 0.5 g corner's roll departs from the hand formula (docs/vehicles_roads.md, "Roll
in the 0.5 g corner"): the cornering run of tests/vehicles/test_full_vehicle_events.py (R = 40 m,
anti-roll bars, flat road), split per axle into the tyres' roll (the measured load transfer
over k_t t^2 / 2) and the suspension's (the wheels' travel relative to the body), the moments
the springs and bars carry (K_s phi_s) and the links' (scrub dy/dz of the contact point at the
measured travels, CornerLinkage), against the series formula of the test.

    PYTHONPATH=. python bench/roll_budget.py      (about 30 s)
"""

from __future__ import annotations

import numpy as np

from cosim.corner import builtin
from nodes.plant.corner_kinematics import CornerLinkage
from nodes.plant.full_vehicle_dw import FullVehicleDoubleWishbone
from nodes.plant.model import GRAVITY
from tests.vehicles.test_full_vehicle_events import H_CG, K_T, M_B, R_L, T, _run

K_W, BARS = 29453.0, (1200.0 * 180 / np.pi, 500.0 * 180 / np.pi)


def scrub(z: float, h: float = 1e-4) -> float:
    """dy/dz [-] of the built-in corner's contact point (r_l down the wheel plane) at travel z."""
    lk = CornerLinkage(builtin())

    def y(zz: float) -> float:
        p = lk.pose(lk.theta_at_travel(zz))
        a = np.asarray(p.spin_axis, float)
        down = np.array([0.0, 0.0, -1.0]) - (-a[2]) * a
        return float((np.asarray(p.wheel_centre, float) + R_L * down / np.linalg.norm(down))[1])
    return (y(z + h) - y(z - h)) / (2 * h)


def main() -> None:
    seen: list[dict[str, np.ndarray]] = []
    state = FullVehicleDoubleWishbone.state

    def spy(self):  # type: ignore[no-untyped-def]
        st = state(self)
        seen.append({k: np.array(st[k], dtype=float) for k in ("z_w", "z_b", "gamma")})
        return st
    FullVehicleDoubleWishbone.state = spy  # type: ignore[method-assign]
    v0 = float(np.sqrt(0.5 * GRAVITY * 40.0))
    _, hist, _, _ = _run(v0 * 3.6, 3.0, speed=[(0.0, v0)], radius=40.0)
    w = hist.t >= 2.0
    st = {k: np.array([s[k] for s in seen])[w].mean(axis=0) for k in seen[0]}
    roll, a_y = float(np.mean(np.abs(hist.roll[w]))), float(np.mean(hist.a_y[w]))
    Fz, Fy = hist.F_z[w].mean(axis=0), hist.F_y[w].mean(axis=0)
    k_tyre = K_T * T ** 2 / 2
    K_s = [K_W * T ** 2 / 2 + b for b in BARS]
    K_ser = [k * k_tyre / (k + k_tyre) for k in K_s]
    arm = H_CG - 0.030
    hand = M_B * a_y * arm / (sum(K_ser) - M_B * GRAVITY * arm)
    print(f"roll {roll:.5f} rad, hand {hand:.5f} (+{roll / hand - 1:.1%}), a_y {a_y:.3f}")
    spring = links = spring_hand = 0.0
    for ax, (lt, rt) in (("front", (0, 1)), ("rear", (2, 3))):
        i = 0 if ax == "front" else 1
        travel = st["z_w"] - st["z_b"]  # wheel's rise relative to the body
        phi_t = (Fz[rt] - Fz[lt]) / 2 * T / k_tyre
        phi_s = roll - phi_t
        phi_t_hand = K_ser[i] * hand / k_tyre
        q = [scrub(float(travel[j])) for j in (lt, rt)]
        m_link = T / 2 * (Fy[lt] * q[0] + Fy[rt] * q[1])
        spring += K_s[i] * phi_s
        spring_hand += K_s[i] * (hand - phi_t_hand)
        links += m_link
        print(f"{ax}: tyre roll {phi_t:.5f} (hand {phi_t_hand:.5f}), suspension roll "
              f"{phi_s:.5f} (hand {hand - phi_t_hand:.5f}); travel in/out {travel[lt]*1e3:+.1f}"
              f"/{travel[rt]*1e3:+.1f} mm, scrub {q[0]:+.3f}/{q[1]:+.3f}, links {m_link:.0f} "
              f"N m (30 mm roll centre: {T / 2 * 0.0418 * (Fy[lt] + Fy[rt]):.0f}), camber "
              f"{st['gamma'][lt]:+.4f}/{st['gamma'][rt]:+.4f} rad")
    total = (Fz[1] - Fz[0] + Fz[3] - Fz[2]) / 2 * T
    contact = float(np.sum(Fz * R_L * np.abs(st["gamma"])))
    print(f"axle moments {total:.0f} N m; springs and bars {spring:.0f} (hand "
          f"{spring_hand:.0f}); links {links:.0f}; "
          f"sum F_z r_l |gamma| {contact:.0f} N m")


if __name__ == "__main__":
    main()
