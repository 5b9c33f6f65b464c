"""Point contact against a fixed footprint on the Ch. 3 step (numerics in
:mod:`nodes.tyre_road.tyre_step_study`): ``python -m orchestrator.studies.tyre_step``."""

from __future__ import annotations

import argparse

from nodes.tyre_road.tyre_step_study import compare


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="tyre-step-study", description=__doc__.splitlines()[0])
    ap.add_argument("--speed-kmh", type=float, default=47.0)
    ap.add_argument("--contact-length", type=float, default=0.2)
    ap.add_argument("-n", type=int, default=4)
    a = ap.parse_args(argv)
    r = compare(a.speed_kmh, a.contact_length, a.n)  # N, ms, %
    print(f"20 mm step, Table 3.1 quarter car, FFP n={a.n}, l_c={a.contact_length} m, "
          f"{a.speed_kmh} km/h ({r['spring_delay_ms']:.2f} ms between springs)\n"
          f"peak tyre force: PC {r['F_pc']:.0f} N, FFP {r['F_ffp']:.0f} N -> PC higher by "
          f"{r['F_diff_pct']:.1f} %; FFP peak lags by {r['lag_ms']:.1f} ms\n"
          f"peak wheel displacement: PC higher by {r['z_w_diff_pct']:.2f} %; body: "
          f"{r['z_b_diff_pct']:.2f} %")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
