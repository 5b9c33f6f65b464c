"""The thesis's Chapter 5 reproduced: the control comparisons and the sine study
(docs/ch5_control_comparison.md).

    python -m bench ch5-compare [SWEEP_FILE] [OUT_DIR]      (or --summarise OUT_DIR)
    python -m bench ch5-pave-tables sweeps/ch5_pave_fvm
    python -m bench ch5-sine-study [--variants]                       (~1-2 min on 2 cores)
    python -m bench ch5-sine-bounds

``ch5-compare`` (Table 5.3): runs a Chapter 5 sweep (default
scenarios/thesis/ch5_mira_lumped.toml, 5 seeds; resumable; OUT_DIR default
sweeps/<sweep name>), ``suscosim ride`` of its runs into OUT_DIR/ride.json, then groups the
points by every grid axis except road.seed (the law: the base scenario
scenarios/ch5_qvm_<law>_random.toml or a ``strategy`` axis): body RMS as the thesis computes
it, the other ride metrics, and the % change against passive on the same seed (Eq 5.13), mean
+- sample std over the seeds. ``--summarise OUT_DIR``: the table of a finished sweep only.

``ch5-pave-tables`` (Tables 5.6-5.11): the full-vehicle pavé sweep (ch5_pave_fvm.toml, after
``ch5-compare scenarios/thesis/ch5_pave_fvm.toml``, which writes ride.json): per corner body
vertical RMS 0-20 and 0-16 Hz, wheel vertical RMS 0-20 Hz, body pitch and roll acceleration RMS
0-16 Hz; passive / TSS1 / PnR at every speed, mean over the seeds and the per-seed % against
passive.

``ch5-sine-study`` (Sec 5.5.1, Figs 5.11-5.17, issue #27 item 2): the laws on the lumped QVM
under 10 mm road sinusoids beside the only numbers the thesis prints for those figures
(tests/controller/data/thesis_ch5_sine.csv): the interval, ours, within 15 %.
``--variants``: also the MR damper unscaled (motion ratio 1) and static (no K_f / M_f).

``ch5-sine-bounds``: the closed-form bounds behind the Figs 5.11-5.15 points our MR model
misses. The linear 2-DOF QVM of Table 4.3 on z_g = A sin(wt), A = 10 mm, with a linear damper
c: |v_rel| = w |Z_b - Z_w|, |a_w| = w^2 |Z_w| from

    [ -m_b w^2 + k_s + i w c,   -(k_s + i w c)              ] [Z_b]   [  0    ]
    [ -(k_s + i w c),   -m_w w^2 + k_s + k_t + i w c        ] [Z_w] = [ k_t A ]

(the switched laws lie between the linear ones); the MR force on the wheel is bounded by the
static bi-viscous law through the motion ratio r: |F| <= r (F_y(I) + c_post(I) r |v_rel|).
"""

from __future__ import annotations

import argparse
import csv
import json
import re
import subprocess
import sys
from collections import defaultdict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cosim.channels import CORNERS  # noqa: E402
from nodes.controller import mr_damper as mr  # noqa: E402
from nodes.controller.laws import build_controller  # noqa: E402
from nodes.plant.equivalent_lumped import TABLE_4_3  # noqa: E402

# ---- ch5-compare ----------------------------------------------------------------------------
_COMPARE_LAWS = ("passive", "tss1", "tss2", "tss3", "pnr")
_COMPARE_KEYS = [
    ("a_b_rms", "body RMS 0-20 Hz [m/s2]"), ("a_b_rms_0_16", "body RMS 0-16 Hz [m/s2]"),
    ("a_b_rms_full", "body RMS full band [m/s2]"), ("a_b_wk_rms", "body Wk RMS [m/s2]"),
    ("jerk_b_rms", "body jerk RMS [m/s3]"), ("a_w_rms", "wheel RMS 0-20 Hz [m/s2]"),
    ("sws", "working space [mm]"), ("dtl_rms", "dynamic tyre load RMS [N]"),
    ("alpha_pitch_rms", "body pitch acc. RMS 0-20 Hz [rad/s2]"),
    ("alpha_pitch_rms_0_16", "body pitch acc. RMS 0-16 Hz [rad/s2]"),
    ("alpha_roll_rms", "body roll acc. RMS 0-20 Hz [rad/s2]"),
    ("alpha_roll_rms_0_16", "body roll acc. RMS 0-16 Hz [rad/s2]")]
_COMPARE_KEYS += [(f"a_arm_{loc}_{ax}_rms", f"arm {name} {ax} RMS 0-20 Hz [m/s2]")
                  for loc, name in (("loc1", "Loc1"), ("cg", "CG"), ("loc2", "Loc2"))
                  for ax in "xyz"]


def _law_of(params: dict) -> str:
    if "strategy" in params:
        return str(params["strategy"])
    m = re.search(r"ch5_\w*?(passive|tss1|tss2|tss3)", str(params.get("base", "")))
    return m.group(1) if m else str(params.get("base"))


def _ch5_summary(out: Path) -> None:
    """The tables of a finished sweep folder ``out`` (its sweep.json and ride.json)."""
    points = json.loads((out / "sweep.json").read_text())["points"]
    ride = {Path(r["path"]).name: r["metrics"]
            for r in json.loads((out / "ride.json").read_text())["runs"]}
    table = defaultdict(lambda: defaultdict(dict))  # group -> law -> seed -> metrics
    for p in points:
        run = Path(p["run_dir"]).name
        if run not in ride:
            continue
        params = dict(p["params"])
        seed = params.pop("road.seed", 0)
        law = _law_of(params)
        params.pop("base", None), params.pop("strategy", None)
        group = ", ".join(f"{k}={v}" for k, v in params.items()) or "all"
        table[group][law][seed] = ride[run]

    for group, laws in table.items():
        print(f"\n## {out.name}: {group}\n")
        base = laws.get("passive", {})
        seeds = sorted(base)
        print(f"seeds: {seeds} (mean +- sample std over the seeds; % = (passive - law) / "
              "passive x 100 on the same seed, positive = reduction)\n")
        order = [law for law in _COMPARE_LAWS if law in laws] + \
            [law for law in laws if law not in _COMPARE_LAWS]
        print("| metric | " + " | ".join(order) + " |")
        print("|---|" + "---|" * len(order))
        first = next(iter(base.values())) if base else {}
        rows = []
        # a full vehicle has the keys per corner: a_b[0]_rms ... a_b[3]_rms
        for key, label in _COMPARE_KEYS:
            if key in first:
                rows.append((key, label))
                continue
            parts = key.split("_")
            n = 2 if parts[0] in ("a", "jerk") else 1
            for i, corner in enumerate(("FL", "FR", "RL", "RR")):
                k = "_".join(parts[:n]) + f"[{i}]" + "".join("_" + q for q in parts[n:])
                if k in first:
                    rows.append((k, f"{label} {corner}"))
        for key, label in rows:
            cells = []
            for law in order:
                vals = np.array([laws[law][s][key] for s in seeds if s in laws[law]])
                if vals.size == 0:
                    cells.append("-")
                    continue
                cell = f"{vals.mean():.4g} ± {vals.std(ddof=1) if vals.size > 1 else 0:.2g}"
                if law != "passive" and all(base[s][key] for s in seeds):  # no % of a zero
                    pct = np.array([(base[s][key] - laws[law][s][key]) / base[s][key] * 100
                                    for s in seeds if s in laws[law]])
                    sd = pct.std(ddof=1) if pct.size > 1 else 0
                    cell += f" ({pct.mean():+.1f} ± {sd:.1f} %, {pct.min():+.1f}…{pct.max():+.1f})"
                cells.append(cell)
            print(f"| {label} | " + " | ".join(cells) + " |")


def ch5_compare(args: argparse.Namespace) -> int:
    """``ch5-compare``: the sweep (unless ``--summarise``), its ride metrics, the tables."""
    if args.summarise:
        out = ROOT / args.summarise
    else:
        out = ROOT / (args.out_dir or f"sweeps/{Path(args.sweep).stem}")
        code = subprocess.run([sys.executable, "-m", "orchestrator", "sweep", args.sweep,
                               "--out", str(out)], cwd=ROOT, stdout=sys.stderr).returncode
        if code:
            return code
    runs = sorted(str(p) for p in (out / "runs").glob("*"))
    ride = subprocess.run([sys.executable, "-m", "orchestrator", "ride", *runs, "--json"],
                          cwd=ROOT, stdout=subprocess.PIPE, text=True)
    if ride.returncode:
        return ride.returncode
    tmp = out / "ride.json.tmp"  # written aside, renamed into place
    tmp.write_text(ride.stdout)
    tmp.replace(out / "ride.json")
    _ch5_summary(out)
    return 0


# ---- ch5-pave-tables ------------------------------------------------------------------------
_PAVE_LAWS = ("passive", "tss1", "pnr")


def ch5_pave_tables(args: argparse.Namespace) -> int:
    """``ch5-pave-tables``: Tables 5.6-5.11 of the full-vehicle pavé sweep."""
    out = args.sweep_out
    points = json.loads((out / "sweep.json").read_text())["points"]
    ride = {Path(r["path"]).name: r["metrics"]
            for r in json.loads((out / "ride.json").read_text())["runs"]}
    data: dict = defaultdict(lambda: defaultdict(dict))  # (law, speed) -> seed -> metrics
    for pt in points:
        run = Path(pt["run_dir"]).name
        if run in ride:
            prm = pt["params"]
            data[(prm["strategy"], float(prm["road.speed_kmh"]))][prm["road.seed"]] = ride[run]
    speeds = sorted({s for _, s in data})
    rows = []
    for key, label in (("a_b[{i}]_rms", "body z 0-20 Hz [m/s2]"),
                       ("a_b[{i}]_rms_0_16", "body z 0-16 Hz [m/s2]"),
                       ("a_w[{i}]_rms", "wheel z 0-20 Hz [m/s2]")):
        rows += [(key.format(i=i), f"{c} {label}") for i, c in enumerate(CORNERS)]
    rows += [("alpha_pitch_rms_0_16", "pitch acc. 0-16 Hz [rad/s2]"),
             ("alpha_roll_rms_0_16", "roll acc. 0-16 Hz [rad/s2]")]
    print("| metric | law | " + " | ".join(f"{s:g} km/h" for s in speeds) + " |")
    print("|---|---|" + "---|" * len(speeds))
    for key, label in rows:
        for law in _PAVE_LAWS:
            cells = []
            for s in speeds:
                base, runs = data[("passive", s)], data[(law, s)]
                seeds = sorted(set(base) & set(runs))
                if not seeds or key not in runs[seeds[0]]:
                    cells.append("-")
                    continue
                v = np.mean([runs[k][key] for k in seeds])
                cell = f"{v:.4g}"
                if law != "passive":
                    pct = [(base[k][key] - runs[k][key]) / base[k][key] * 100 for k in seeds]
                    cell += f" ({np.mean(pct):+.1f} %)"
                cells.append(cell)
            print(f"| {label} | {law} | " + " | ".join(cells) + " |")
    n = {k: len(v) for k, v in data.items()}
    print(f"\nseeds per (law, speed): {sorted(set(n.values()))}")
    return 0


# ---- the sine study's model ------------------------------------------------------------------
# The thesis ran Sec 5.5.1 "in MATLAB/Simulink" on the lumped 2-DOF QVM of Table 4.3 (m_b =
# 535 kg, m_w = 47.75 kg, k_s = 31 kN/m, k_t = 239 kN/m), z_g = A sin(2 pi f t), A = 10 mm,
# passive 1500 N s/m against TSS1-3. Here with the package's own controllers (built from a
# ``[controller]`` table by nodes.controller.laws.build_controller: the MR damper and the laws
# of a co-simulation run) on a 2-DOF quarter car integrated here (no PyBullet):
#
#     m_b z_b'' = -k_s (z_b - z_w) + F_d
#     m_w z_w'' =  k_s (z_b - z_w) - F_d + max(-W, k_t (z_g - z_w))   (deviations; lift-off)
#
# F_d on the body (up +), W = (m_b + m_w) g. Each step h the controller gives F_d at t_k and its
# slope c_eff; between steps F_d + c_eff (v_rel - v_rel,k) (the co-simulation's Jacobian
# coupling), classical RK4 in ``substeps``. The figures carry no digitised data: what can be
# compared is in tests/controller/data/thesis_ch5_sine.csv and docs/ch5_control_comparison.md.
GRAVITY = 9.81  # m/s^2

#: The thesis's laws on the lumped QVM (Table 5.2 lumped pair; the MR damper scaled by the
#: lumped model's motion ratio 0.628, as in scenarios/ch5_qvm_tss{2,3}_random.toml).
THESIS_LAWS: dict[str, dict[str, Any]] = {
    "passive": {"law": "passive", "c": 1500.0},
    "tss1": {"law": "tss1", "preset": "lumped"},
    "tss2": {"law": "tss2", "preset": "lumped", "damper": {"motion_ratio": 0.628}},
    "tss3": {"law": "tss3", "I_soft": 0.0, "I_hard": 0.6, "damper": {"motion_ratio": 0.628}},
}
#: The frequencies of Figs 5.11-5.15 (Hz).
THESIS_FREQUENCIES = (1.0, 1.5, 5.0, 10.0, 12.0, 15.0)


@dataclass(frozen=True)
class QuarterCar:
    """Lumped 2-DOF QVM, Table 4.3 (SI units: :data:`nodes.plant.equivalent_lumped.TABLE_4_3`)."""

    m_b: float = TABLE_4_3["m_b"]
    m_w: float = TABLE_4_3["m_w"]
    k_s: float = TABLE_4_3["k_s"]
    k_t: float = TABLE_4_3["k_t"]


CAR = QuarterCar()


def sine_response(law: Mapping[str, Any], freqs: Sequence[float], *, amplitude: float = 0.01,
                  h: float = 5e-4, substeps: int = 4, t_end: float | None = None,
                  car: QuarterCar = CAR) -> dict[str, np.ndarray]:
    """Quarter cars on z_g = amplitude [m] sin(2 pi f t), one per frequency [Hz], from rest,
    as the independent "corners" of one controller built from the ``[controller]`` table
    ``law``; ``h`` [s] (the MR laws need 0.5 ms, Sec 5.3.3); ``t_end`` default 6 s (the body
    transient, 1/(zeta omega) = 0.7 s, decayed to 0.02 %) plus 3 periods of the lowest f.

    Returns histories of shape (steps + 1, len(freqs)): ``z_g``, ``z_b``, ``z_w`` [m],
    ``v_rel`` [m/s], ``F_d`` [N, on the body], ``a_b``, ``a_w`` [m/s^2], ``I`` [A, NaN
    without current]; ``t`` [s] of shape (steps + 1,)."""
    f = np.asarray(freqs, dtype=float).reshape(-1)
    if f.size == 0 or np.any(f <= 0) or amplitude <= 0 or h <= 0:
        raise ValueError(f"freqs, amplitude and h must be > 0, got {freqs}, {amplitude}, {h}")
    m = f.size
    ctrl = build_controller(dict(law), m, h)
    T = 6.0 + 3.0 / float(f.min()) if t_end is None else t_end
    n = int(round(T / h))
    w = 2 * np.pi * f
    W = (car.m_b + car.m_w) * GRAVITY
    y = np.zeros((4, m))  # z_b, v_b, z_w, v_w

    def rhs(t: float, y: np.ndarray, F0: np.ndarray, c: np.ndarray,
            vr0: np.ndarray) -> np.ndarray:
        z_b, v_b, z_w, v_w = y
        F_d = F0 + c * ((v_w - v_b) - vr0)
        F_s = car.k_s * (z_w - z_b)
        F_t = np.maximum(-W, car.k_t * (amplitude * np.sin(w * t) - z_w))
        return np.array([v_b, (F_s + F_d) / car.m_b, v_w, (F_t - F_s - F_d) / car.m_w])

    keys = ("z_g", "z_b", "z_w", "v_rel", "F_d", "a_b", "a_w", "I")
    out = {k: np.empty((n + 1, m)) for k in keys}
    out["t"] = np.arange(n + 1) * h  # type: ignore[assignment]  # 1-D, the others 2-D
    dt = h / substeps
    try:
        for k in range(n + 1):
            t = k * h
            co = ctrl.step(t, {"z_b": y[0], "v_b": y[1], "z_w": y[2], "v_w": y[3]})
            F0, c = np.asarray(co.F_d, dtype=float), np.asarray(co.c_eff, dtype=float)
            vr0 = y[3] - y[1]
            acc = rhs(t, y, F0, c, vr0)
            out["z_g"][k] = amplitude * np.sin(w * t)
            out["z_b"][k], out["z_w"][k], out["v_rel"][k] = y[0], y[2], vr0
            out["F_d"][k], out["a_b"][k], out["a_w"][k] = F0, acc[1], acc[3]
            out["I"][k] = co.extra["I"] if "I" in co.extra else np.nan
            if k == n:
                break
            for j in range(substeps):
                s = t + j * dt
                k1 = rhs(s, y, F0, c, vr0)
                k2 = rhs(s + dt / 2, y + dt / 2 * k1, F0, c, vr0)
                k3 = rhs(s + dt / 2, y + dt / 2 * k2, F0, c, vr0)
                k4 = rhs(s + dt, y + dt * k3, F0, c, vr0)
                y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    finally:
        ctrl.close()
    return out


def steady(r: Mapping[str, np.ndarray], freqs: Sequence[float], i: int,
           periods: float = 2.0) -> dict[str, np.ndarray]:
    """Frequency ``i``'s last ``periods`` periods of a :func:`sine_response` record."""
    t = r["t"]
    keep = t >= t[-1] - periods / float(freqs[i])
    return {k: (v[keep] if k == "t" else v[keep, i]) for k, v in r.items()}


def rms(x: np.ndarray) -> float:
    """Root mean square of a steady record [its unit]."""
    return float(np.sqrt(np.mean(np.square(x))))


# ---- ch5-sine-bounds ------------------------------------------------------------------------
A = 0.01  # m, road sine amplitude (Sec 5.5.1)


def linear_amplitudes(f: float, c: float, car: QuarterCar = CAR) -> tuple[float, float]:
    """Steady (|v_rel| [m/s], |a_w| [m/s^2]) of the linear 2-DOF at f [Hz] with damper c."""
    w = 2.0 * np.pi * f
    ks = car.k_s + 1j * w * c
    M = np.array([[-car.m_b * w**2 + ks, -ks], [-ks, -car.m_w * w**2 + ks + car.k_t]])
    zb, zw = np.linalg.solve(M, np.array([0.0, car.k_t * A]))
    return float(w * abs(zb - zw)), float(w**2 * abs(zw))


def ch5_sine_bounds(args: argparse.Namespace) -> int:
    """``ch5-sine-bounds``: the linear 2-DOF amplitudes and the MR force bound."""
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


# ---- ch5-sine-study -------------------------------------------------------------------------
DATA = ROOT / "tests" / "controller" / "data" / "thesis_ch5_sine.csv"
RMS_FREQS = (1.0, 1.5, 2.0, 3.0, 5.0, 8.0, 10.0, 12.0, 15.0)
#: the plotted time window of Figs 5.13-5.15 (their time axes) per frequency [s]
WINDOW = {1.0: 2.0, 1.5: 2.0, 5.0: 0.5, 10.0: 0.3, 12.0: 0.3, 15.0: 0.3}


def _sine_rows() -> list[dict[str, str]]:
    with DATA.open() as fh:
        return list(csv.DictReader(fh))


def simulate(laws: dict[str, dict], freqs=THESIS_FREQUENCIES) -> dict[str, dict]:
    return {name: sine_response(law, freqs) for name, law in laws.items()}


def _sine_window(r: dict, freqs, i: int) -> dict[str, np.ndarray]:
    keep = r["t"] <= WINDOW[float(freqs[i])] + 1e-12
    return {k: (v[keep] if k == "t" else v[keep, i]) for k, v in r.items()}


def ours(row: dict[str, str], runs: dict[str, dict], freqs, rms_runs: dict[str, dict],
         p: mr.MRParams) -> float:
    """Our value of one thesis number (see the CSV's quantity column)."""
    q, laws = row["quantity"], row["laws"].split()
    if row["figure"] == "Table 5.1":
        return {"T51_cpost0": float(mr.c_post(0.0, p)), "T51_cpost06": float(mr.c_post(0.6, p)),
                "T51_fy0": float(mr.yield_force(0.0, p)),
                "T51_fy06": float(mr.yield_force(0.6, p)), "T51_cpre": p.c_pre}[row["id"]]
    if row["id"] == "S541_soft":
        return float(mr.c_post(0.0, p))
    if row["id"] == "S541_hard":
        return float(mr.c_post(0.6, p))
    if q.startswith("max over f"):
        key = "a_b" if "body" in q else "a_w"
        return max(rms(steady(rms_runs[law], RMS_FREQS, i)[key])
                   for law in laws for i in range(len(RMS_FREQS)))
    i = list(freqs).index(float(row["f_hz"]))
    key = {"|F_d|": "F_d", "|v_rel|": "v_rel", "|a_w|": "a_w", "I": "I"}[q.split()[1]]
    return max(float(np.nanmax(np.abs(_sine_window(runs[law], freqs, i)[key]))) for law in laws)


def _sine_table(laws: dict[str, dict], label: str) -> list[tuple[str, float, float, float, bool]]:
    runs = simulate(laws)
    rms_runs = {name: sine_response(law, RMS_FREQS) for name, law in laws.items()}
    p = mr.MRParams()
    out = []
    for row in _sine_rows():
        lo, hi = float(row["lo"]), float(row["hi"])
        v = ours(row, runs, THESIS_FREQUENCIES, rms_runs, p)
        ok = 0.85 * lo <= v <= 1.15 * hi
        out.append((row["id"], lo, hi, v, ok))
    print(f"\n{label}\n| thesis number | interval | ours | within 15 % |\n|---|---|---|---|")
    for rid, lo, hi, v, ok in out:
        iv = f"{lo:g}" if lo == hi else f"({lo:g}, {hi:g}]"
        print(f"| {rid} | {iv} | {v:.4g} | {'yes' if ok else 'NO'} |")
    return out


def qualitative(laws: dict[str, dict]) -> None:
    """Sec 5.5.1's statements on Figs 5.16 / 5.17, body and wheel RMS per frequency."""
    res = {name: sine_response(law, RMS_FREQS) for name, law in laws.items()}
    print("\n| f [Hz] | " + " | ".join(f"{n} body / wheel RMS" for n in laws) + " |")
    print("|---|" + "---|" * len(laws))
    for i, f in enumerate(RMS_FREQS):
        cells = [f"{rms(steady(res[n], RMS_FREQS, i)['a_b']):.3f} / "
                 f"{rms(steady(res[n], RMS_FREQS, i)['a_w']):.2f}" for n in laws]
        print(f"| {f:g} | " + " | ".join(cells) + " |")


def ch5_sine_study(args: argparse.Namespace) -> int:
    """``ch5-sine-study``: the laws under road sinusoids against the thesis's numbers."""
    _sine_table(THESIS_LAWS, "shipped laws (MR motion ratio 0.628, K_f / M_f dynamics)")
    qualitative(THESIS_LAWS)
    if args.variants:
        for label, damper in (("MR unscaled (motion ratio 1)", {"motion_ratio": 1.0}),
                              ("MR static (no K_f / M_f)", {"motion_ratio": 0.628,
                                                            "dynamics": False}),
                              ("MR unscaled and static", {"motion_ratio": 1.0,
                                                          "dynamics": False})):
            laws = dict(THESIS_LAWS)
            for k in ("tss2", "tss3"):
                laws[k] = {**THESIS_LAWS[k], "damper": damper}
            _sine_table(laws, label)
    return 0



def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("ch5-compare", help="Table 5.3: a Chapter 5 sweep's ride comparison")
    p.add_argument("sweep", nargs="?", default="scenarios/thesis/ch5_mira_lumped.toml",
                   help="the sweep file (relative: to the repository root)")
    p.add_argument("out_dir", nargs="?", default=None, help="default sweeps/<sweep name>")
    p.add_argument("--summarise", metavar="OUT_DIR", default=None,
                   help="only the tables of a finished sweep folder")
    p.set_defaults(fn=ch5_compare)
    p = sub.add_parser("ch5-pave-tables", help="Tables 5.6-5.11 of the full-vehicle pavé sweep")
    p.add_argument("sweep_out", type=Path, help="the sweep folder (with ride.json)")
    p.set_defaults(fn=ch5_pave_tables)
    p = sub.add_parser("ch5-sine-study", help="Figs 5.11-5.17: the laws under road sinusoids")
    p.add_argument("--variants", action="store_true",
                   help="also the MR damper unscaled and static")
    p.set_defaults(fn=ch5_sine_study)
    p = sub.add_parser("ch5-sine-bounds", help="closed-form bounds of the sine study")
    p.set_defaults(fn=ch5_sine_bounds)
    args = ap.parse_args(argv)
    return int(args.fn(args) or 0)


if __name__ == "__main__":
    raise SystemExit(main())
