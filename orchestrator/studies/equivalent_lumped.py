"""``suscosim equivalent-lumped``: the equivalent lumped quarter car of the double-wishbone
corner (log decrement, Appendix II; numerics in :mod:`nodes.plant.equivalent_lumped`)."""

from __future__ import annotations

import argparse
import json

from cosim import corner as corner_file
from cosim.errors import SuscosimError
from nodes.plant.equivalent_lumped import TABLE_4_3, compare_on_road, identify

from ..cli_util import fail


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="equivalent-lumped", description=__doc__.splitlines()[0])
    ap.add_argument("--step", type=float, default=0.01, help="road step height [m]")
    ap.add_argument("--dt", type=float, default=1e-3, help="time step [s]")
    ap.add_argument("--no-compare", action="store_true", help="skip the road comparison")
    ap.add_argument("--corner", default=None, metavar="FILE",
                    help="corner file (default: the built-in MPV corner; docs/corners.md)")
    ap.add_argument("--json", action="store_true",
                    help="print one JSON object (SI units): k_s, c_s, m_s, m_u, ...")
    args = ap.parse_args(argv)
    corner = None
    if args.corner is not None:
        try:
            corner = corner_file.load(args.corner)
        except SuscosimError as exc:
            return fail("suscosim equivalent-lumped", str(exc), exc.exit_code)
    eq = identify(args.step, args.dt, corner=corner)
    cmp = None if args.no_compare else compare_on_road(eq, args.dt, corner=corner)
    if args.json:
        out = {"k_s": eq["k_s"], "c_s": eq["c_s"], "m_s": eq["m_b"], "m_u": eq["m_w"],
               "k_t": eq["k_t"], "zeta": eq["zeta"], "f_n": eq["f_n"], "delta": eq["delta"],
               "T": eq["T"], "k_s_app2": eq["k_s_app2"], "c_s_app2": eq["c_s_app2"],
               "k_s_lever": eq["k_s_lever"], "c_s_lever": eq["c_s_lever"],
               "k_s_error_pct": 100 * (eq["k_s"] / TABLE_4_3["k_s"] - 1),
               "c_s_error_pct": 100 * (eq["c_s"] / TABLE_4_3["c_s"] - 1),
               "table_4_3": {"k_s": TABLE_4_3["k_s"], "c_s": TABLE_4_3["c_s"],
                             "m_s": TABLE_4_3["m_b"], "m_u": TABLE_4_3["m_w"],
                             "k_t": TABLE_4_3["k_t"], "ride_rate": TABLE_4_3["ride_rate"]},
               "step_m": args.step, "dt_s": args.dt}
        if cmp is not None:
            out["road_comparison"] = cmp
        print(json.dumps(out, indent=1))
        return 0
    print(f"log decrement: delta = {eq['delta']:.3f}, zeta = {eq['zeta']:.3f}, "
          f"T = {eq['T']:.3f} s, f_n = {eq['f_n']:.3f} Hz ({int(eq['n_extrema'])} extrema)")
    print(f"{'parameter':<40}{'identified':>12}{'Table 4.3':>12}")
    rows = [("m_b [kg]", eq["m_b"], TABLE_4_3["m_b"]), ("m_w [kg]", eq["m_w"], TABLE_4_3["m_w"]),
            ("k_s, 2-DOF equivalent [N/m]", eq["k_s"], TABLE_4_3["k_s"]),
            ("c_s, 2-DOF equivalent [N s/m]", eq["c_s"], TABLE_4_3["c_s"]),
            ("M_b w_n^2 (App. II) [N/m] ~ ride rate", eq["k_s_app2"], TABLE_4_3["ride_rate"]),
            ("zeta 2 sqrt(k M_b) (App. II) [N s/m]", eq["c_s_app2"], None),
            ("k_t [N/m]", eq["k_t"], TABLE_4_3["k_t"])]
    for name, a, b in rows:
        print(f"{name:<40}{a:>12.1f}" + (f"{b:>12.1f}" if b is not None else f"{'-':>12}"))
    print(f"geometry at the ball joint: K_theta / L^2 = {eq['k_s_lever']:.0f} N/m "
          f"(L = {eq['lever_m']:.3f} m), C (MR cos lean)^2 = {eq['c_s_lever']:.0f} N s/m "
          f"(lean {eq['damper_lean_deg']:.1f} deg)")
    if cmp is not None:
        print("realistic vs equivalent lumped (2-DOF k_s, c_s), Ch. 4 bump + pothole at 34 km/h:")
        for key in ("z_b", "z_w"):
            print(f"  {key}: peak {cmp[f'{key}_peak_realistic'] * 1e3:.2f} mm realistic, "
                  f"{cmp[f'{key}_peak_lumped'] * 1e3:.2f} mm lumped "
                  f"({cmp[f'{key}_peak_diff_pct']:+.1f} %), RMS difference "
                  f"{cmp[f'{key}_rms_diff_pct_of_peak']:.1f} % of the peak")
    return 0
