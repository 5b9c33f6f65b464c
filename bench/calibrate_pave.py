"""Calibrate the synthetic pavé (nodes/tyre_road/cobblestone.py) against thesis Table 4.5.

The passive realistic double-wishbone corner of ``scenarios/thesis/ch6_realistic_qvm.toml``
(h = 0.5 ms, 34 km/h, point-contact tyre 239 kN/m, c = 3800 N s/m on the damper velocity) is
run in-process (``run.mode = "monolithic"``: the real node code on an in-memory bus, live
fatigue off) over the pavé with candidate parameters; the hub (plant/response/a_w) and body
(plant/response/a_b) vertical accelerations are reduced by the thesis's metric (resampled to
500 Hz, one-sided boxcar periodogram, RMS = sqrt(trapz) over 0-20 Hz, Eq. 4.8/4.9:
``nodes.recorder.ride_metrics.thesis_band_rms``) and compared with Table 4.5:
hub 59.216 m/s^2, body 3.2274 m/s^2.

Usage::

    python bench/calibrate_pave.py                        # the defaults, seeds 1 2 3
    python bench/calibrate_pave.py --G 5e-6 1e-5 --stone-height-std 0.004 0.006
    python bench/calibrate_pave.py --search               # solve for (G, s_h), then check
    python bench/calibrate_pave.py --scenario scenarios/ch4_qvm_realistic_pave.toml \
        --length 350                                      # Table 4.5's own set-up: 350 m, 2 ms

``--search``: the two parameters act mostly on different responses (G, the long waves, on the
body; s_h, the random stone heights, on the wheel hop), and a linear system's mean-square
responses are linear in the input PSD levels (G and s_h^2). So the search evaluates a 2 x 2
design of (G, s_h^2), fits hub^2 and body^2 as linear in (G, s_h^2) (seed-averaged), solves
for the targets, and repeats the fit about the solution (a Newton step on the mean squares)
until both seed-mean RMS are within 3 % (at most ``--iterations``). The bump stop makes the
corner non-linear, hence the iteration. Never tune to fatigue lives: only these two ride
numbers enter.
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

HUB_TABLE_4_5 = 59.216
BODY_TABLE_4_5 = 3.2274
"""Thesis Table 4.5, z vertical, 0-20 Hz RMS [m/s^2] (LTC pavé, 350 m, 34 km/h)."""

HUB_BANDS: tuple[tuple[float, float], ...] = (
    (0.0, 5.0), (5.0, 10.0), (10.0, 15.0), (15.0, 20.0), (20.0, 30.0), (30.0, 40.0),
    (40.0, 50.0), (0.0, 45.8), (0.0, 50.0))
"""Hub bands [Hz] reported beside the 0-20 Hz RMS (issue #27 item 4: the arm's damage comes
from content to ~50 Hz). 0-45.8 Hz is what App. IV's hard-coded bins q = 1..3000 reach for the
350 m record (N = 18 529, nfft = 2^15 at 500 Hz; thesis-ch4 Sec. 4.5)."""

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "thesis" / "ch6_realistic_qvm.toml"


def corner_rms(road: dict, workdir: Path, scenario: Path = SCENARIO) -> dict[str, float]:
    """Run the passive corner of ``scenario`` on ``road`` (a [road] table) in-process and
    return the thesis's 0-20 Hz RMS of the hub and body vertical accelerations [m/s^2]."""
    import pyarrow.parquet as pq

    from cosim import scenario as sc
    from nodes.recorder.ride_metrics import thesis_band_rms
    from orchestrator.runner import resolve, run_scenario

    cfg = sc.load(scenario, ['run.mode="monolithic"', "fatigue.live=false",
                             'controller.law="passive"', "controller.c=3800.0",
                             'controller.velocity="damper"'])
    cfg["road"] = dict(road)
    out = Path(tempfile.mkdtemp(prefix="pave_", dir=workdir))
    cfg = resolve(cfg, out)
    summary = run_scenario(cfg, quiet=True)
    if summary.get("status") != "ok":
        raise RuntimeError(f"run failed: {summary.get('error')}")
    table = pq.read_table(out / "table.parquet")
    t = table["t"].to_numpy()
    a_w = table["plant/response/a_w"].to_numpy()
    res = {"hub": thesis_band_rms(t, a_w),
           "body": thesis_band_rms(t, table["plant/response/a_b"].to_numpy())}
    res.update(hub_band_levels(t, a_w))
    if "plant/response/F_bs" in table.column_names:  # the thesis's pave hit the bump stop
        f_bs = table["plant/response/F_bs"].to_numpy()
        res["bump_stop_share"] = float(np.mean(f_bs > 0.0))
        res["bump_stop_peak_n"] = float(f_bs.max())
    f_t = table["tyre_road/force/F_t"].to_numpy()
    res["lift_off_share"] = float(np.mean(f_t <= 0.0))
    for f in out.iterdir():  # the run folder is not kept (21 000 rows x 30 channels)
        f.unlink()
    out.rmdir()
    return res


def hub_band_levels(t: np.ndarray, a_w: np.ndarray) -> dict[str, float]:
    """The hub vertical acceleration ``a_w`` [m/s^2] at times ``t`` [s] reduced by the
    thesis's metric in each of :data:`HUB_BANDS` (keys ``hub_F1_F2`` [m/s^2]), and the
    frequency [Hz] of the largest Welch PSD value in 5-50 Hz (``hub_peak_hz``: the raw
    periodogram's peak is a single noisy bin, thesis Sec. 4.6.2)."""
    from scipy.signal import welch

    from nodes.recorder.ride_metrics import THESIS_FS, periodogram_band_rms, resample_to

    x = resample_to(t, a_w, THESIS_FS)
    out = {f"hub_{f1:g}_{f2:g}": periodogram_band_rms(x, THESIS_FS, (f1, f2))
           for f1, f2 in HUB_BANDS}
    f, P = welch(x, fs=THESIS_FS, nperseg=min(1024, x.size))
    keep = (f >= 5.0) & (f <= 50.0)
    out["hub_peak_hz"] = float(f[keep][np.argmax(P[keep])])
    return out


def pave_road_cfg(G: float, s_h: float, seed: int, length_m: float, **extra) -> dict:
    """A [road] table of the pavé with long-wave level ``G`` and stone height scatter ``s_h``."""
    return {"type": "pave", "speed_kmh": 34.0, "length_m": length_m, "seed": seed,
            "G": G, "stone_height_std": s_h, **extra}


def evaluate(G: float, s_h: float, seeds: list[int], length_m: float, workdir: Path,
             log=print, scenario: Path = SCENARIO) -> dict:
    """Hub and body RMS per seed, and their mean and spread (sample std), for (G, s_h)."""
    per_seed = []
    for seed in seeds:
        r = corner_rms(pave_road_cfg(G, s_h, seed, length_m), workdir, scenario)
        per_seed.append({"seed": seed, **r})
        log(f"  G = {G:.4g}  s_h = {s_h * 1e3:.3f} mm  seed {seed}: "
            f"hub {r['hub']:7.2f}  body {r['body']:6.3f} m/s^2  (tyre off the road "
            f"{r['lift_off_share']:.1%} of the time; bump stop engaged "
            f"{r.get('bump_stop_share', float('nan')):.1%}, peak "
            f"{r.get('bump_stop_peak_n', float('nan')):.0f} N)")
        log("    hub bands " + "  ".join(f"{f1:g}-{f2:g} Hz {r[f'hub_{f1:g}_{f2:g}']:.2f}"
                                         for f1, f2 in HUB_BANDS)
            + f"  Welch peak {r['hub_peak_hz']:.1f} Hz")
    hub = np.array([r["hub"] for r in per_seed])
    body = np.array([r["body"] for r in per_seed])
    out: dict[str, Any] = {"G": G, "stone_height_std": s_h, "per_seed": per_seed,
           "hub_mean": float(hub.mean()), "body_mean": float(body.mean()),
           "hub_std": float(hub.std(ddof=1)) if hub.size > 1 else 0.0,
           "body_std": float(body.std(ddof=1)) if body.size > 1 else 0.0}
    log(f"  -> hub {out['hub_mean']:.2f} +- {out['hub_std']:.2f} "
        f"({out['hub_mean'] / HUB_TABLE_4_5 - 1:+.1%} vs 59.216), "
        f"body {out['body_mean']:.3f} +- {out['body_std']:.3f} "
        f"({out['body_mean'] / BODY_TABLE_4_5 - 1:+.1%} vs 3.2274)")
    return out


def solve_linear(points: list[dict]) -> tuple[float, float]:
    """(G, s_h) at which the least-squares fits hub^2, body^2 = a + b G + c s_h^2 through the
    evaluated ``points`` meet Table 4.5 (the offset a is kept only with more than 3 points)."""
    X = np.array([[p["G"], p["stone_height_std"] ** 2] for p in points])
    A = np.column_stack([np.ones(len(points)), X]) if len(points) > 3 else X
    rows = []
    for key in ("hub_mean", "body_mean"):
        y = np.array([p[key] ** 2 for p in points])
        rows.append(np.linalg.lstsq(A, y, rcond=None)[0])
    coef = np.array(rows)
    offset = coef[:, 0] if coef.shape[1] == 3 else np.zeros(2)
    M = coef[:, -2:]
    target = np.array([HUB_TABLE_4_5 ** 2, BODY_TABLE_4_5 ** 2]) - offset
    G, s2 = np.linalg.solve(M, target)
    if G <= 0 or s2 <= 0:
        raise RuntimeError(f"linear fit gives no positive solution (G {G:.3g}, s_h^2 {s2:.3g})")
    return float(G), float(np.sqrt(s2))


def search(G0: float, s0: float, seeds: list[int], length_m: float, workdir: Path,
           iterations: int, log=print) -> tuple[dict, list[dict]]:
    """The --search procedure of the module docstring; returns (final point, all points)."""
    points = [evaluate(G, s, seeds, length_m, workdir, log)
              for G, s in itertools.product((G0, 2.0 * G0), (s0, s0 * np.sqrt(2.0)))]
    best: dict | None = None
    for _ in range(iterations):
        G, s = solve_linear(points[-4:] if best is None else points)
        log(f"fit -> G = {G:.4g}, s_h = {s * 1e3:.3f} mm")
        best = evaluate(G, s, seeds, length_m, workdir, log)
        points.append(best)
        if (abs(best["hub_mean"] / HUB_TABLE_4_5 - 1) < 0.03
                and abs(best["body_mean"] / BODY_TABLE_4_5 - 1) < 0.03):
            break
    if best is None:
        raise ValueError("--iterations must be at least 1")
    return best, points


def main(argv: list[str] | None = None) -> int:
    from nodes.tyre_road.cobblestone import DEFAULTS

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--G", type=float, nargs="+", default=[DEFAULTS.G],
                    help="long-wave level(s) G [m^0.5] (default: the pavé default)")
    ap.add_argument("--stone-height-std", type=float, nargs="+",
                    default=[DEFAULTS.stone_height_std],
                    help="stone height scatter(s) s_h [m] (default: the pavé default)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--length", type=float, default=100.0, help="road length [m]")
    ap.add_argument("--scenario", type=Path, default=SCENARIO,
                    help="base scenario (default scenarios/thesis/ch6_realistic_qvm.toml; "
                         "the check at 2 ms: scenarios/ch4_qvm_realistic_pave.toml with "
                         "--length 350)")
    ap.add_argument("--search", action="store_true",
                    help="solve for (G, s_h) from the first --G and --stone-height-std")
    ap.add_argument("--iterations", type=int, default=4)
    ap.add_argument("--json", help="write every evaluated point to this file")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="calibrate_pave_") as tmp:
        work = Path(tmp)
        if args.search:
            best, points = search(args.G[0], args.stone_height_std[0], args.seeds,
                                  args.length, work, args.iterations)
            print(f"calibrated: G = {best['G']:.4g}, stone_height_std = "
                  f"{best['stone_height_std']:.5f} m")
        else:
            points = [evaluate(G, s, args.seeds, args.length, work, scenario=args.scenario)
                      for G, s in itertools.product(args.G, args.stone_height_std)]
    if args.json:
        Path(args.json).write_text(json.dumps(points, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
