"""Accuracy of the co-simulation against the reference solution (Eq. 3.5's peak errors), and its
cost: the Chapter 3 quarter car over its 20 mm step. Timing is measured here, never asserted in
tests.

    python -m bench cosim [--steps 0.001,0.002,0.003,0.004,0.005] [--repeat 1]
                          [--coupling jacobian] [--out bench/out]
    python -m bench coupling [--steps 0.001,0.002,0.005]
    python -m bench coupling-residual [--steps 0.00025,0.0005,0.001,0.002,0.004] [--csv OUT.csv]
    python -m bench adaptive-step [--out /tmp/adaptive_step] [--coupling hold]   (~2 min)
    python -m bench roll-budget

``cosim`` (thesis Tables 3.2 and 3.3): for each communication step h, the wall time of the
reference (solve_ivp), monolithic (the one-process engine, no bus) and distributed (4 node processes
over Zenoh on loopback) runs, coupled steps/s, and the peak errors of the distributed run
against the reference (true peaks on a 20 us grid); rows also in ``OUT/bench_cosim.json``.

``coupling``: the coupling mode (hold, linear, jacobian) and exchange order against accuracy:
monolithic runs (the node code and numbers of a distributed run without the transport), worst
peak error per signal.

``coupling-residual`` (issue #29): does the coupling's energy residual predict the error? For
every exchange order, coupling mode and h (monolithic): the worst peak error against the
reference (the true error) beside the energy residual of :mod:`cosim.coupling_energy`
(relative, per bond and in total), which needs no reference. A markdown table.

``adaptive-step`` (issue #29 item 3): ``run.h = "auto"`` against fixed steps on the lumped
quarter car, for the Ch 3 step and the Ch 4 bump + pothole with the coupling ``hold`` (its
error is the coupling's, which the residual measures): fixed h = 0.25 ... 4 ms and ``auto`` at
several tolerances, monolithic; per run the communication steps and the worst peak error of
Table 3.3's signals against the reference mode. A markdown table, and its JSON in ``--out``.

``roll-budget`` (issue #44): where the 0.5 g corner's roll departs from the hand formula
(docs/vehicles_roads.md, "Roll in the 0.5 g corner"): the cornering run of
tests/vehicles/test_full_vehicle_events.py (R = 40 m, anti-roll bars, flat road), split per
axle into the tyres' roll (the measured load transfer over k_t t^2 / 2) and the suspension's
(the wheels' travel relative to the body), the moments the springs and bars carry
(K_s phi_s) and the links' (scrub dy/dz of the contact point at the measured travels,
CornerLinkage), against the series formula of the test (about 30 s).
"""

from __future__ import annotations

import argparse
import csv
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cosim import coupling_energy as ce  # noqa: E402
from cosim import scenario as sc  # noqa: E402
from cosim.table import read_table  # noqa: E402
from orchestrator.accuracy import peak_errors, worst  # noqa: E402
from orchestrator.reference import reference_solution  # noqa: E402
from orchestrator.runner import resolve, run_scenario  # noqa: E402

SCENARIO = ROOT / "scenarios" / "ch3_step_quarter_car.toml"


# ---- cosim ----------------------------------------------------------------------------------
def _timed_run(out: Path, overrides: list[str]) -> tuple[dict, dict]:
    s = resolve(sc.load(SCENARIO, overrides), out)
    t0 = time.perf_counter()
    summary = run_scenario(s, quiet=True)
    summary["bench_wall_s"] = time.perf_counter() - t0
    return s, summary


def cosim(args: argparse.Namespace) -> int:
    """``cosim``: Tables 3.2 and 3.3."""
    out = Path(args.out)
    steps = [float(x) for x in args.steps.split(",")]
    scenario = resolve(sc.load(SCENARIO), out / "probe")
    ref = reference_solution(scenario, np.arange(0, 4.0 + 1e-9, 2e-5))
    rows = []
    for h in steps:
        base = [f"run.h={h}", f'run.coupling="{args.coupling}"']
        _, r = _timed_run(out / f"ref-{h}", base + ['run.mode="reference"'])
        _, m = _timed_run(out / f"mono-{h}", base + ['run.mode="monolithic"'])
        best = None
        for i in range(args.repeat):
            _, d = _timed_run(out / f"dist-{h}-{i}", base)
            if best is None or d["steps_per_s"] > best["steps_per_s"]:
                best, best_dir = d, out / f"dist-{h}-{i}"
        err = peak_errors(read_table(best_dir / "table.parquet"), ref, t_from=0.4)
        rows.append({"h": h, "reference_s": r["bench_wall_s"], "monolithic_s": m["bench_wall_s"],
                     "distributed_s": best["bench_wall_s"],
                     "distributed_steps_per_s": best["steps_per_s"],
                     "monolithic_steps_per_s": m["steps_per_s"],
                     "worst_peak_error_pct": worst(err), "errors": err})
    print("\nTable 3.2 (ours): wall time [s] of the 4 s Chapter 3 step run")
    print(f"{'h [s]':>7} {'reference':>10} {'monolithic':>11} {'distributed':>12} "
          f"{'dist steps/s':>13} {'mono steps/s':>13}")
    for r in rows:
        print(f"{r['h']:>7} {r['reference_s']:>10.2f} {r['monolithic_s']:>11.2f} "
              f"{r['distributed_s']:>12.2f} {r['distributed_steps_per_s']:>13.0f} "
              f"{r['monolithic_steps_per_s']:>13.0f}")
    print("\nTable 3.3 (ours): peak error of the distributed run against the reference [%]")
    labels = list(rows[0]["errors"])
    print(f"{'h [s]':>7} " + " ".join(f"{lab[:18] + ' ' + k:>24}" for lab in labels
                                      for k in rows[0]["errors"][lab]))
    for r in rows:
        print(f"{r['h']:>7} " + " ".join(f"{r['errors'][lab][k]:>24.3f}" for lab in labels
                                        for k in r["errors"][lab]))
    (out / "bench_cosim.json").write_text(json.dumps(rows, indent=2, default=float))
    return 0


# ---- coupling -------------------------------------------------------------------------------
def coupling(args: argparse.Namespace) -> int:
    """``coupling``: worst peak error per exchange order, coupling mode and h."""
    tmp = Path(tempfile.mkdtemp(prefix="suscosim-coupling-"))
    ref = reference_solution(resolve(sc.load(SCENARIO), tmp / "p"),
                             np.arange(0, 4.0 + 1e-9, 2e-5))
    print(f"{'exchange':>10} {'coupling':>9} {'h [s]':>6}  worst |peak error| [%] "
          "(z_b max, z_w max, a_w max/min, F_t max/min)")
    for exchange in ("sequential", "parallel"):
        for coupling in ("hold", "linear", "jacobian"):
            for h in (float(x) for x in args.steps.split(",")):
                d = tmp / f"{exchange}-{coupling}-{h}"
                s = resolve(sc.load(SCENARIO, [f"run.h={h}", f'run.coupling="{coupling}"',
                                               f'run.exchange="{exchange}"',
                                               'run.mode="monolithic"']), d)
                run_scenario(s, quiet=True)
                e = peak_errors(read_table(d / "table.parquet"), ref, t_from=0.4)
                flat = [e[k][m] for k in e for m in e[k]]
                print(f"{exchange:>10} {coupling:>9} {h:>6} {worst(e):8.3f}   "
                      + " ".join(f"{v:+.2f}" for v in flat))
    return 0


# ---- coupling-residual ----------------------------------------------------------------------
def study(steps: list[float], tmp: Path) -> list[dict[str, float | str]]:
    """One row per (exchange, coupling, h): true worst peak error and the residuals [%]."""
    ref = reference_solution(resolve(sc.load(SCENARIO), tmp / "p"),
                             np.arange(0, 4.0 + 1e-9, 2e-5))
    rows: list[dict[str, float | str]] = []
    for exchange in ("sequential", "parallel"):
        for coupling in ("hold", "linear", "jacobian"):
            for h in steps:
                d = tmp / f"{exchange}-{coupling}-{h}"
                s = resolve(sc.load(SCENARIO, [f"run.h={h}", f'run.coupling="{coupling}"',
                                               f'run.exchange="{exchange}"',
                                               'run.mode="monolithic"']), d)
                run_scenario(s, quiet=True)
                table = read_table(d / "table.parquet")
                res = ce.summary(ce.coupling_residual(table, h, coupling, exchange))
                rows.append({"exchange": exchange, "coupling": coupling, "h": h,
                             "true_peak_error_pct": worst(peak_errors(table, ref, t_from=0.4)),
                             **{f"residual_{b}_pct": 100 * v for b, v in res.items()}})
    return rows


def coupling_residual(args: argparse.Namespace) -> int:
    """``coupling-residual``: the energy residual beside the true error."""
    rows = study([float(x) for x in args.steps.split(",")],
                 Path(tempfile.mkdtemp(prefix="suscosim-residual-")))
    print("| exchange | coupling | h [ms] | true worst peak error [%] | residual damper [%] "
          "| residual tyre [%] | residual total [%] | total / true |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        true, tot = float(r["true_peak_error_pct"]), float(r["residual_total_pct"])
        ratio = f"{tot / true:.2f}" if true > 0 else "-"
        print(f"| {r['exchange']} | {r['coupling']} | {1e3 * float(r['h']):g} | {true:.3f} "
              f"| {float(r.get('residual_damper_pct', 0)):.3g} "
              f"| {float(r.get('residual_tyre_pct', 0)):.3g} | {tot:.3g} | {ratio} |")
    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    return 0


# ---- adaptive-step --------------------------------------------------------------------------
BUMP_POTHOLE = ('road={type="events", speed_kmh=34.0, length_m=15.0, events=['
                '{type="bump", height=0.05, length=1.0, x_start=3.0}, '
                '{type="pothole", depth=0.04, length=0.6, x_start=10.0, shape="cosine"}]}')
ROADS = {"step": [], "bump_pothole": ["--set", BUMP_POTHOLE, "--set", "run.t_end=0"]}
FIXED_MS = (0.25, 0.5, 1.0, 2.0, 4.0)
TOLS = (1e-2, 3e-3, 1e-3, 3e-4)


def _adaptive_run(out: Path, *sets: str) -> dict:
    if not (out / "summary.json").is_file():
        r = subprocess.run([sys.executable, "-m", "orchestrator", "run",
                            str(ROOT / "scenarios" / "ch3_step_quarter_car.toml"), "--out",
                            str(out), "--quiet", *sets], capture_output=True, text=True,
                           cwd=ROOT)
        if r.returncode != 0:
            raise SystemExit(f"{out}: {r.stderr[-2000:]}")
    return json.loads((out / "summary.json").read_text())


def adaptive_step(args: argparse.Namespace) -> int:
    """``adaptive-step``: ``run.h = "auto"`` against fixed steps."""
    rows = []
    for road, road_sets in ROADS.items():
        base = [*road_sets, "--set", f'run.coupling="{args.coupling}"']
        ref_dir = args.out / road / "reference"
        _adaptive_run(ref_dir, *base, "--mode", "reference", "--set", "run.h=0.00025")
        ref = read_table(ref_dir / "table.parquet")
        cases = [(f"fixed {ms:g} ms", ["--set", f"run.h={ms / 1000:g}"]) for ms in FIXED_MS]
        cases += [(f"auto tol {tol:g}", ["--set", 'run.h="auto"', "--set", f"run.h_tol={tol:g}"])
                  for tol in TOLS]
        for label, sets in cases:
            d = args.out / road / label.replace(" ", "_")
            s = _adaptive_run(d, *base, "--mode", "monolithic", *sets)
            err = worst(peak_errors(read_table(d / "table.parquet"), ref, t_from=0.0))
            a = s.get("adaptive_step", {})
            rows.append({"road": road, "run": label, "steps": s["n_steps"],
                         "worst_peak_error_pct": err,
                         "residual_pct": 100 * s.get("coupling_energy_residual", {})
                         .get("total", float("nan")),
                         "h_smallest_ms": 1e3 * a["h_smallest"] if a else None,
                         "h_largest_ms": 1e3 * a["h_largest"] if a else None})
    print("| road | run | steps | worst peak error | residual | h range [ms] |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        hr = (f"{r['h_smallest_ms']:.3g}-{r['h_largest_ms']:.3g}" if r["h_smallest_ms"]
              else "")
        print(f"| {r['road']} | {r['run']} | {r['steps']} | {r['worst_peak_error_pct']:.3f} % "
              f"| {r['residual_pct']:.3g} % | {hr} |")
    args.out.mkdir(parents=True, exist_ok=True)
    tmp = args.out / "adaptive_step.json.tmp"
    tmp.write_text(json.dumps(rows, indent=1))
    tmp.replace(args.out / "adaptive_step.json")
    return 0


# ---- roll-budget ----------------------------------------------------------------------------
K_W, BARS = 29453.0, (1200.0 * 180 / np.pi, 500.0 * 180 / np.pi)


def scrub(z: float, h: float = 1e-4) -> float:
    """dy/dz [-] of the built-in corner's contact point (r_l down the wheel plane) at travel z."""
    from cosim.corner import builtin
    from nodes.plant.corner_kinematics import CornerLinkage
    from tests.vehicles.test_full_vehicle_events import R_L

    lk = CornerLinkage(builtin())

    def y(zz: float) -> float:
        p = lk.pose(lk.theta_at_travel(zz))
        a = np.asarray(p.spin_axis, float)
        down = np.array([0.0, 0.0, -1.0]) - (-a[2]) * a
        return float((np.asarray(p.wheel_centre, float) + R_L * down / np.linalg.norm(down))[1])
    return (y(z + h) - y(z - h)) / (2 * h)


def roll_budget(args: argparse.Namespace) -> int:
    """``roll-budget``: the 0.5 g corner's roll, split per axle, against the hand formula."""
    from nodes.plant.full_vehicle_dw import FullVehicleDoubleWishbone
    from nodes.plant.model import GRAVITY
    from tests.vehicles.test_full_vehicle_events import H_CG, K_T, M_B, R_L, T, _run

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
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("cosim", help="Tables 3.2, 3.3: wall time and peak error per step h")
    p.add_argument("--steps", default="0.001,0.002,0.003,0.004,0.005")
    p.add_argument("--repeat", type=int, default=1, help="distributed runs per step (best kept)")
    p.add_argument("--coupling", default="jacobian")
    p.add_argument("--out", default=str(ROOT / "bench" / "out"))
    p.set_defaults(fn=cosim)
    p = sub.add_parser("coupling", help="peak error per coupling mode and exchange order")
    p.add_argument("--steps", default="0.001,0.002,0.005")
    p.set_defaults(fn=coupling)
    p = sub.add_parser("coupling-residual", help="the energy residual beside the true error")
    p.add_argument("--steps", default="0.00025,0.0005,0.001,0.002,0.004")
    p.add_argument("--csv", help="also write the rows to this CSV file")
    p.set_defaults(fn=coupling_residual)
    p = sub.add_parser("adaptive-step", help="run.h = 'auto' against fixed steps")
    p.add_argument("--out", type=Path, default=Path("/tmp/adaptive_step"))
    p.add_argument("--coupling", default="hold")
    p.set_defaults(fn=adaptive_step)
    p = sub.add_parser("roll-budget", help="the 0.5 g corner's roll against the hand formula")
    p.set_defaults(fn=roll_budget)
    args = ap.parse_args(argv)
    return int(args.fn(args) or 0)


if __name__ == "__main__":
    raise SystemExit(main())
