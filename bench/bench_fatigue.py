"""Throughput of the fatigue chain: node-samples per second.

Synthetic 37 s x 500 Hz load history (the thesis's pavé track length in time) on the default
built-in arm, all surface nodes: superposition, equivalent stress, rainflow, Miner.

    python bench/bench_fatigue.py [--equivalent signed_von_mises] [--method strain_life]
    python bench/bench_fatigue.py --run RUN_DIR [--screen 0.01] [--engine turning]

``--run``: CPU time (process_time, not wall) per coupled step of the live engine fed a run's
recorded ``plant/arm`` loads in blocks of ``fatigue.block_samples`` as the live node does
(e.g. a Ch 6 realistic-corner run folder), unscreened and with ``--screen`` f.
``--engine turning``: the worker's block loop as proposed for #28 (the equivalent stress
exactly only where rainflow needs it, :mod:`nodes.fatigue.turning_eq`), patched in here until
``worker._Engine._exact`` carries it; ``--engine both`` runs the two back to back.
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
    p.add_argument("--run", default=None, help="a run folder: live engine CPU per step")
    p.add_argument("--screen", type=float, default=0.01)
    p.add_argument("--engine", choices=("block", "turning", "both"), default="block")
    a = p.parse_args()
    if a.run:
        for eng in (("block", "turning") if a.engine == "both" else (a.engine,)):
            _use_engine(eng)
            print(f"engine {eng}:")
            _run_cpu(a.run, a.screen)
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


_BLOCK_EXACT = None


def _use_engine(kind: str) -> None:
    """Patch ``_Engine._exact`` with the turning-point path (the diff proposed for worker.py)
    or restore the block path."""
    import numpy as np

    from nodes.fatigue import worker
    from nodes.fatigue.superposition import ROWS, superpose_components
    from nodes.fatigue.turning_eq import turning_equivalent

    global _BLOCK_EXACT
    if _BLOCK_EXACT is None:
        _BLOCK_EXACT = worker._Engine._exact
    if kind == "block":
        worker._Engine._exact = _BLOCK_EXACT  # type: ignore[method-assign]
        return

    def _exact(self, F, idx, rf):  # type: ignore[no-untyped-def]
        if idx.size == 0:
            return
        coef = self.per_node[idx]
        rows = max(ROWS, (2_000_000 // (6 * idx.size)) // ROWS * ROWS)
        hi = np.full(idx.size, -np.inf)
        lo = np.full(idx.size, np.inf)
        for i in range(0, F.shape[0], rows):
            pts, last, bhi, blo = turning_equivalent(
                superpose_components(F[i:i + rows], coef), self.cfg.equivalent, rf.last)
            np.maximum(hi, bhi, out=hi)
            np.minimum(lo, blo, out=lo)
            self._add(rf.feed_points(pts, last), idx, self.damage, self.ncyc, self.rmax)
        self.eq_max[idx] = np.maximum(self.eq_max[idx], hi)
        self.eq_min[idx] = np.minimum(self.eq_min[idx], lo)
        if self.scr is not None:
            self.scr.envelope(idx, hi, lo)

    worker._Engine._exact = _exact  # type: ignore[method-assign]


def _run_cpu(run: str, screen: float) -> None:
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
    for f in (None, screen):
        live = LiveFatigue(cfg, names, 1.0, screen=f, total_samples=t.size)
        c0 = time.process_time()
        for i in range(0, t.size, n):
            live.update(t[i:i + n], arr[i:i + n])
        r = live.result()
        cpu = time.process_time() - c0
        print(f"screen {f}: {cpu / t.size * 1e6:.0f} us CPU per step over {t.size} steps, "
              f"critical node {r.critical_node_id}, screened {r.screening.get('screened_nodes')}")


if __name__ == "__main__":
    main()
