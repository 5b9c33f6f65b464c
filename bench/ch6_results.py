"""Chapter 6 tables from a finished ``ch6_fatigue`` sweep: minimum life of the lower arm per
road and strategy (km and repeats of the track), the change against passive on the same road
realisation, mean and spread over the pavé seeds, the critical node and where it is, and the
ten most damaged nodes (thesis Tables 6.3-6.6; docs/REPRODUCTION.md, Chapter 6).

    python bench/ch6_results.py sweeps/ch6_fatigue
    python bench/ch6_results.py sweeps/ch6_fatigue --fatigue-root DIR   # DIR/<run>/summary.json

``--fatigue-root``: the fatigue results of each run in ``DIR/<run folder name>/`` (e.g. the
batch ``suscosim fatigue RUN --part ... --out DIR/<run>`` of every run on another part or mesh)
in place of the runs' own ``fatigue/``. A third table gives the life by both component S-N
methods (Shigley/Marin and FKM) at P = 0.5 and 0.975 (``summary.json`` ``sn_methods``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

STRATEGIES = ("passive", "tss1", "tss2", "tss3")


def load(sweep_dir: Path, root: Path | None = None) -> dict[tuple[str, str], dict]:
    """{(road, strategy): fatigue summary} of the sweep's finished points (from ``root``'s
    per-run folders when given)."""
    doc = json.loads((sweep_dir / "sweep.json").read_text())
    out = {}
    for p in doc["points"]:
        run = sweep_dir / p["run_dir"]
        f = (root / run.name if root else run / "fatigue") / "summary.json"
        if f.is_file():
            out[(p["params"]["road"], p["params"]["strategy"])] = json.loads(f.read_text())
    return out


def _node_str(s: dict) -> str:
    x, y, z = (1000 * v for v in s["critical_node_xyz_m"])
    return f"{s['critical_node_id']} ({x:.0f}, {y:.0f}, {z:.0f}) mm"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sweep_dir", type=Path)
    ap.add_argument("--fatigue-root", type=Path, default=None,
                    help="per-run fatigue results in DIR/<run folder name>/")
    args = ap.parse_args(argv)
    if not (args.sweep_dir / "sweep.json").is_file():
        print(f"error: {args.sweep_dir}: no sweep.json (not a sweep folder)", file=sys.stderr)
        return 2
    res = load(args.sweep_dir, args.fatigue_root)
    roads = sorted({r for r, _ in res})
    print("| road | strategy | min life [km] | repeats | change vs passive | critical node |"
          " ten most damaged nodes |")
    print("|---|---|---|---|---|---|---|")
    changes: dict[tuple[str, str], list[float]] = {}
    for road in roads:
        base = res.get((road, "passive"))
        for s in STRATEGIES:
            r = res.get((road, s))
            if r is None:
                print(f"| {road} | {s} | (missing) | | | | |")
                continue
            ch = "—"
            if base is not None and s != "passive":
                c = 100.0 * (r["min_life_km"] / base["min_life_km"] - 1.0)
                ch = f"{c:+.0f} %"
                group = "pave" if road.startswith("pave") else road
                changes.setdefault((group, s), []).append(c)
            top = ", ".join(str(t["node_id"] if isinstance(t, dict) else t)
                            for t in r["top_nodes"][:10])
            print(f"| {road} | {s} | {r['min_life_km']:.4g} | {r['min_life_repeats']:.4g} | "
                  f"{ch} | {_node_str(r)} | {top} |")
    print()
    print("| road | strategy | change vs passive: mean ± sd over realisations (n) |")
    print("|---|---|---|")
    for (g, s), v in sorted(changes.items()):
        a = np.asarray(v)
        sd = a.std(ddof=1) if a.size > 1 else 0.0
        print(f"| {g} | {s} | {a.mean():+.1f} ± {sd:.1f} % ({a.size}) |")
    pav = [res[(r, "passive")]["min_life_km"] for r in roads
           if r.startswith("pave") and (r, "passive") in res]
    if pav:
        print(f"\npassive pavé min life: {np.mean(pav):.0f} km mean over {len(pav)} seeds "
              f"({min(pav):.0f}-{max(pav):.0f}); thesis Table 6.3: 1279 km")
    print()
    print("| road | strategy | Shigley P50 [km] | Shigley P97.5 | FKM P50 | FKM P97.5 | "
          "FKM / Shigley (P50) |")
    print("|---|---|---|---|---|---|---|")
    for road in roads:
        for s in STRATEGIES:
            m = (res.get((road, s)) or {}).get("sn_methods", {}).get("methods")
            if not m:
                continue
            life = {(k, p): m[k][p]["life_km"] for k in ("shigley", "fkm") if k in m
                    for p in ("0.5", "0.975") if p in m[k]}
            cells = [f"{life[(k, p)]:.4g}" if (k, p) in life else "–"
                     for k in ("shigley", "fkm") for p in ("0.5", "0.975")]
            ratio = (life[("fkm", "0.5")] / life[("shigley", "0.5")]
                     if ("fkm", "0.5") in life and ("shigley", "0.5") in life else float("nan"))
            print(f"| {road} | {s} | " + " | ".join(cells) + f" | {ratio:.3g} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
