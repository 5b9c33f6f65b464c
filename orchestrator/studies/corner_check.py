"""``suscosim corner check FILE [--json]``: a corner file's kinematic and compliance curves
(camber, toe, damper motion ratio, wheel rate and load against wheel travel), its gains at ride
height, lateral compliance and equivalent lumped quarter car (:mod:`nodes.plant.corner_kinematics`;
docs/corners.md). ``--identify``: also the PyBullet corner's log-decrement quarter car.
"""

from __future__ import annotations

import argparse
import json
import math
from typing import Any

import numpy as np

from cosim import corner as corner_file
from cosim.errors import InputFileError, SuscosimError

from ..cli_util import fail

DEG = 180.0 / math.pi


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="suscosim corner", description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="action", required=True)
    c = sub.add_parser("check", help="curves, gains and equivalent quarter car of a corner "
                       "file ('builtin': the MPV corner)")
    c.add_argument("file", help="corner TOML file, or 'builtin'")
    c.add_argument("--json", action="store_true", help="one JSON object, SI units")
    c.add_argument("--travel", type=float, nargs=2, default=(-0.08, 0.08),
                   metavar=("REBOUND", "JOUNCE"), help="wheel travel range [m] (-0.08 0.08)")
    c.add_argument("--points", type=int, default=17, help="points on the curves (17)")
    c.add_argument("--tyre-stiffness", type=float, default=239000.0,
                   help="k_t for the quarter car's frequencies [N/m] (Table 4.3: 239000)")
    c.add_argument("--identify", action="store_true",
                   help="also the PyBullet corner's log-decrement quarter car (seconds)")
    return ap


def check(corner: corner_file.Corner, travel: tuple[float, float], n: int, k_t: float,
          identify: bool = False) -> dict[str, Any]:
    """Everything ``corner check`` prints, SI (unreachable travels listed)."""
    from nodes.plant import corner_kinematics as ck

    rows: dict[str, list[float]] = {}
    unreachable = []
    for z in np.linspace(travel[0], travel[1], n):
        try:
            cv = ck.curves(corner, np.array([z]))
        except ValueError:
            unreachable.append(float(z))
            continue
        for key, v in cv.items():
            rows.setdefault(key, []).append(float(v[0]))
    h = 0.005
    g = ck.curves(corner, np.array([-h, 0.0, h]))
    eq = ck.equivalent_quarter_car(corner)
    m_s, m_u, k_s = eq["m_s"], eq["m_u"], eq["k_s"]
    ride = k_s * k_t / (k_s + k_t)
    out: dict[str, Any] = {
        "corner": corner.name, "source": corner.source, "half_track_m": corner.half_track,
        "curves": rows, "unreachable_travel_m": unreachable, "ride_height": {
            "camber_gain_rad_per_m": float((g["camber"][2] - g["camber"][0]) / (2 * h)),
            "bump_steer_rad_per_m": float((g["toe"][2] - g["toe"][0]) / (2 * h)),
            "mr_damper": eq["mr_damper"], "wheel_rate_n_per_m": k_s,
            "wheel_rate_elastic_n_per_m": eq["k_s_elastic"],
            "wheel_load_n": float(g["wheel_load"][1])},
        "equivalent_quarter_car": {
            "m_s": m_s, "m_u": m_u, "k_s": k_s, "c_s": eq["c_s"], "k_t": k_t,
            "ride_rate": ride, "f_body_hz": math.sqrt(ride / m_s) / (2 * math.pi),
            "f_wheel_hz": math.sqrt((k_s + k_t) / m_u) / (2 * math.pi),
            "zeta_body": eq["c_s"] / (2 * math.sqrt(ride * m_s))},
        "lateral_compliance": ck.lateral_compliance(corner),
    }
    if identify:
        from nodes.plant.equivalent_lumped import identify as ident
        r = ident(corner=corner)
        out["identified_quarter_car"] = {k: r[k] for k in ("k_s", "c_s", "m_b", "m_w", "zeta",
                                                           "f_n")}
    return out


def _print(r: dict[str, Any]) -> None:
    cv = r["curves"]
    print(f"corner {r['corner']} ({r['source']}), half track {r['half_track_m']:.4f} m")
    print("kinematics and compliance against wheel travel (body held; jounce +):")
    print(f"{'z_w mm':>8}{'arm deg':>9}{'camber deg':>11}{'toe deg':>9}{'MR_d':>8}"
          f"{'k_w N/mm':>10}{'elastic':>9}{'F_w N':>9}{'F_bs N':>9}")
    for i in range(len(cv.get("z_w", []))):
        print(f"{cv['z_w'][i] * 1e3:8.1f}{cv['theta'][i] * DEG:9.3f}{cv['camber'][i] * DEG:11.3f}"
              f"{cv['toe'][i] * DEG:9.4f}{cv['mr_damper'][i]:8.4f}"
              f"{cv['wheel_rate'][i] / 1e3:10.2f}{cv['wheel_rate_elastic'][i] / 1e3:9.2f}"
              f"{cv['wheel_load'][i]:9.0f}{cv['bump_stop_force'][i]:9.0f}")
    if r["unreachable_travel_m"]:
        print("  the linkage does not reach z_w = "
              + ", ".join(f"{z * 1e3:.0f}" for z in r["unreachable_travel_m"]) + " mm")
    rh = r["ride_height"]
    print(f"at ride height: camber gain {rh['camber_gain_rad_per_m'] * DEG / 10:.3f} deg/100 mm"
          f", bump steer {rh['bump_steer_rad_per_m'] * DEG / 10:.4f} deg/100 mm (toe-in +), "
          f"MR_d {rh['mr_damper']:.4f}, wheel rate {rh['wheel_rate_n_per_m'] / 1e3:.2f} N/mm "
          f"(elastic {rh['wheel_rate_elastic_n_per_m'] / 1e3:.2f}: K_theta / z'^2 + k_c MR_s^2; "
          f"the rest is the preload through the lever's change)")
    eq = r["equivalent_quarter_car"]
    print(f"equivalent quarter car: m_s {eq['m_s']:.2f} kg, m_u {eq['m_u']:.2f} kg, "
          f"k_s {eq['k_s']:.0f} N/m, c_s {eq['c_s']:.0f} N s/m; with k_t {eq['k_t']:.0f} N/m: "
          f"ride rate {eq['ride_rate']:.0f} N/m, body {eq['f_body_hz']:.3f} Hz "
          f"(zeta {eq['zeta_body']:.3f}), wheel hop {eq['f_wheel_hz']:.2f} Hz")
    lc = r["lateral_compliance"]
    if isinstance(lc, dict):
        print(f"lateral compliance (bushes' radial rates, F_y at the contact patch): wheel "
              f"centre {lc['lateral_stiffness_wc'] / 1e6:.2f} kN/mm, camber "
              f"{lc['camber_compliance'] * DEG * 1e3:+.4f} deg/kN (outward force)")
    else:
        print("lateral compliance: the file gives no bushes")
    ident = r.get("identified_quarter_car")
    if isinstance(ident, dict):
        print(f"PyBullet corner, log decrement: k_s {ident['k_s']:.0f} N/m, "
              f"c_s {ident['c_s']:.0f} N s/m, zeta {ident['zeta']:.3f}, f_n {ident['f_n']:.3f} Hz")


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        corner = (corner_file.builtin() if args.file == "builtin"
                  else corner_file.load(args.file, "corner file"))
        if args.points < 2:
            raise InputFileError("--points", "at least 2 points")
        if not args.tyre_stiffness > 0:
            raise InputFileError("--tyre-stiffness", "a stiffness > 0 N/m")
        if not args.travel[0] < args.travel[1]:
            raise InputFileError("--travel", "REBOUND < JOUNCE")
        r = check(corner, tuple(args.travel), args.points, args.tyre_stiffness, args.identify)
    except SuscosimError as exc:
        return fail("suscosim corner", str(exc), exc.exit_code)
    except ValueError as exc:  # the linkage does not close at ride height
        return fail("suscosim corner", f"{args.file}: {exc}")
    if args.json:
        print(json.dumps(r, indent=1))
    else:
        _print(r)
    return 0
