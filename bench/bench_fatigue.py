"""Throughput of the fatigue chain: node-samples per second.

Synthetic 37 s x 500 Hz load history (the thesis's pavé track length in time) on the default
built-in arm, all surface nodes: superposition, equivalent stress, rainflow, Miner.

    python bench/bench_fatigue.py [--equivalent signed_von_mises] [--method strain_life]
"""

from __future__ import annotations

import argparse
import time

from nodes.fatigue.config import FatigueConfig
from nodes.fatigue.synthetic import pave_like_loads
from nodes.fatigue.worker import analyse, load_influence


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--equivalent", default="abs_max_principal")
    p.add_argument("--method", default="stress_life")
    p.add_argument("--mean-stress", default="goodman")
    p.add_argument("--nodes", default="surface")
    a = p.parse_args()
    cfg = FatigueConfig.from_dict({"equivalent": a.equivalent, "method": a.method,
                                   "mean_stress": a.mean_stress, "nodes": a.nodes})
    t0 = time.perf_counter()
    inf = load_influence(cfg)
    t_inf = time.perf_counter() - t0
    t, loads = pave_like_loads(37.0, 500.0)
    t0 = time.perf_counter()
    r = analyse(t, loads, cfg, 350.0)
    dt = time.perf_counter() - t0
    ns = inf.n_nodes * t.size
    print(f"influence (cache or cold FE build): {t_inf:.2f} s; {inf.n_nodes} nodes, "
          f"{len(inf.case_names)} load cases")
    print(f"chain: {t.size} samples x {inf.n_nodes} nodes = {ns:.3g} node-samples in {dt:.2f} s"
          f" -> {ns / dt:.3g} node-samples/s ({a.equivalent}, {a.method}, {a.mean_stress})")
    print(f"min life {r.life_km:.3g} km, critical node {r.critical_node_id}")


if __name__ == "__main__":
    main()
