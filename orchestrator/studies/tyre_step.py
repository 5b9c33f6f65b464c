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
    print(summary(compare(a.speed_kmh, a.contact_length, a.n), a.speed_kmh, a.contact_length, a.n))
    return 0


def summary(r: dict[str, float], speed_kmh: float, contact_length: float, n: int) -> str:
    """The study's three lines: the run's settings, the peak tyre forces and their lag, the
    peak displacements (``r`` from :func:`~nodes.tyre_road.tyre_step_study.compare`: N, ms, %)."""
    return "\n".join([
        f"20 mm step, Table 3.1 quarter car, FFP n={n}, l_c={contact_length} m, {speed_kmh} "
        f"km/h ({r['spring_delay_ms']:.2f} ms between springs)",
        f"peak tyre force: PC {r['F_pc']:.0f} N, FFP {r['F_ffp']:.0f} N -> PC higher by "
        f"{r['F_diff_pct']:.1f} %; FFP peak lags by {r['lag_ms']:.1f} ms",
        f"peak wheel displacement: PC higher by {r['z_w_diff_pct']:.2f} %; body: "
        f"{r['z_b_diff_pct']:.2f} %",
    ])


if __name__ == "__main__":
    raise SystemExit(main())
