"""Throughput of the fatigue chain: node-samples per second.

Synthetic 37 s x 500 Hz load history (the thesis's pavé track length in time) on the default
built-in arm, all surface nodes: superposition, equivalent stress, rainflow, Miner.

    python -m bench fatigue [--equivalent signed_von_mises] [--method strain_life]
    python -m bench fatigue --run RUN_DIR [--screen 0.01] [--repeat 3]

``--run``: CPU time (process_time, not wall) per coupled step of the live engine fed a run's
recorded ``plant/arm`` loads in blocks of ``fatigue.block_samples`` as the live node does
(e.g. a Ch 6 realistic-corner run folder), unscreened and with ``--screen`` f (``--screen 0``:
unscreened only); every repeat's damage, extremes, ranges and cycle counts are checked
``array_equal`` to the first's (the numpy oracles the tests compare the engine with are in
``tests/fatigue/oracle_turning_eq.py``, not a product path). The numba kernels are compiled
(or loaded from their cache) by ``worker.warm_up()`` before the clock starts (as the live
node does before it is ready): the time is printed.
"""

from __future__ import annotations

import argparse
import time

_T_IMPORT = time.perf_counter()
from nodes.fatigue import worker  # noqa: E402  (the numba kernels compile or load here)
from nodes.fatigue.config import FatigueConfig  # noqa: E402
from nodes.fatigue.synthetic import pave_like_loads  # noqa: E402
from nodes.fatigue.worker import analyse, load_influence  # noqa: E402

_T_IMPORT = time.perf_counter() - _T_IMPORT


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--equivalent", default="abs_max_principal")
    p.add_argument("--method", default="stress_life")
    p.add_argument("--mean-stress", default="goodman")
    p.add_argument("--nodes", default="surface")
    p.add_argument("--run", default=None, help="a run folder: live engine CPU per step")
    p.add_argument("--screen", type=float, default=0.01)
    p.add_argument("--repeat", type=int, default=1, help="repeats (--run)")
    a = p.parse_args()
    if a.run:
        from nodes.fatigue.lib import counting

        t0 = time.perf_counter()
        worker.warm_up()
        print(f"import of the worker {_T_IMPORT:.2f} s, warm_up {time.perf_counter() - t0:.2f}"
              f" s wall (numba kernels, compiled or from the cache: {counting.COMPILE_S})")
        first: dict = {}
        for _ in range(a.repeat):
            _run_cpu(a.run, a.screen, first)
        return
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


def _run_cpu(run: str, screen: float, first: dict) -> None:
    import json
    from pathlib import Path

    import numpy as np

    from nodes.fatigue.run_dir import read_table
    from nodes.fatigue.worker import LiveFatigue

    sc = json.loads((Path(run) / "scenario.json").read_text())
    cfg = FatigueConfig.from_dict(sc.get("fatigue"))
    t, loads = read_table(Path(run))
    names = list(loads)
    arr = np.stack([loads[c] for c in names], axis=1)
    n = cfg.block_samples
    for f in (None, screen) if screen else (None,):
        live = LiveFatigue(cfg, names, 1.0, screen=f, total_samples=t.size)
        c0 = time.process_time()
        for i in range(0, t.size, n):
            live.update(t[i:i + n], arr[i:i + n])
        r = live.result()
        cpu = time.process_time() - c0
        got = [r.damage, r.eq_max, r.eq_min, r.eq_range_max, r.n_cycles]
        ref = first.setdefault(f, got)
        same = all(np.array_equal(x, y, equal_nan=True) for x, y in zip(ref, got, strict=True))
        print(f"screen {f}: {cpu / t.size * 1e6:.0f} us CPU per step over {t.size} steps, "
              f"critical node {r.critical_node_id}, screened {r.screening.get('screened_nodes')}"
              f", array_equal to the first repeat: {same}")


if __name__ == "__main__":
    main()
