"""Where the realistic corner meets its jounce bumper (numerics in
:mod:`nodes.plant.bump_stop_study`): ``python -m orchestrator.studies.bump_stop [--json]``."""

from __future__ import annotations

import argparse
import json

from nodes.plant.bump_stop_study import study


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="bump-stop-study", description=__doc__.splitlines()[0])
    ap.add_argument("--dt", type=float, default=1e-3, help="time step [s]")
    ap.add_argument("--json", action="store_true", help="print one JSON object (SI units)")
    args = ap.parse_args(argv)
    r = study(args.dt)
    if args.json:
        print(json.dumps(r, indent=1))
        return 0
    fc = r["first_contact"]
    print(f"first contact: {fc['jounce_m'] * 1e3:.1f} mm of wheel jounce (relative to the "
          f"body), arm angle {fc['arm_angle_deg']:.2f} deg")
    for c, v in r["ch4_bump_pothole"].items():
        print(f"Ch. 4 bump + pothole, c = {c} N s/m: jounce {v['jounce_max_m'] * 1e3:.1f} mm, "
              f"F_bs max {v['F_bs_max']:.0f} N")
    v = r["bump_100mm"]
    print(f"100 mm x 1.0 m bump, c = 3800 N s/m: jounce {v['jounce_max_m'] * 1e3:.1f} mm, "
          f"F_bs max {v['F_bs_max']:.0f} N")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
