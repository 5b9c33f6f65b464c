"""Thesis Sec 5.5.1 (Figs 5.11-5.17): the laws on the lumped QVM under 10 mm road sinusoids,
beside the only numbers the thesis prints for those figures (tests/controller/data/
thesis_ch5_sine.csv: Table 5.1, the text's 3800 / 6000 N s/m, the panels' axis ranges).

    python bench/ch5_sine_study.py [--variants]      (issue #27 item 2; ~1-2 min on 2 cores)

--variants adds the MR damper unscaled (motion ratio 1) and static (no K_f / M_f dynamics).
Prints one row per thesis number: the interval, ours, and whether ours is within 15 % of it.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from nodes.controller import mr_damper as mr  # noqa: E402
from nodes.controller.sine_study import (  # noqa: E402
    THESIS_FREQUENCIES,
    THESIS_LAWS,
    rms,
    sine_response,
    steady,
)

DATA = ROOT / "tests" / "controller" / "data" / "thesis_ch5_sine.csv"
RMS_FREQS = (1.0, 1.5, 2.0, 3.0, 5.0, 8.0, 10.0, 12.0, 15.0)
#: the plotted time window of Figs 5.13-5.15 (their time axes) per frequency [s]
WINDOW = {1.0: 2.0, 1.5: 2.0, 5.0: 0.5, 10.0: 0.3, 12.0: 0.3, 15.0: 0.3}


def rows() -> list[dict[str, str]]:
    with DATA.open() as fh:
        return list(csv.DictReader(fh))


def simulate(laws: dict[str, dict], freqs=THESIS_FREQUENCIES) -> dict[str, dict]:
    return {name: sine_response(law, freqs) for name, law in laws.items()}


def window(r: dict, freqs, i: int) -> dict[str, np.ndarray]:
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
    return max(float(np.nanmax(np.abs(window(runs[law], freqs, i)[key]))) for law in laws)


def table(laws: dict[str, dict], label: str) -> list[tuple[str, float, float, float, bool]]:
    runs = simulate(laws)
    rms_runs = {name: sine_response(law, RMS_FREQS) for name, law in laws.items()}
    p = mr.MRParams()
    out = []
    for row in rows():
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


def main() -> int:
    table(THESIS_LAWS, "shipped laws (MR motion ratio 0.628, K_f / M_f dynamics)")
    qualitative(THESIS_LAWS)
    if "--variants" in sys.argv:
        for label, damper in (("MR unscaled (motion ratio 1)", {"motion_ratio": 1.0}),
                              ("MR static (no K_f / M_f)", {"motion_ratio": 0.628,
                                                            "dynamics": False}),
                              ("MR unscaled and static", {"motion_ratio": 1.0,
                                                          "dynamics": False})):
            laws = dict(THESIS_LAWS)
            for k in ("tss2", "tss3"):
                laws[k] = {**THESIS_LAWS[k], "damper": damper}
            table(laws, label)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
