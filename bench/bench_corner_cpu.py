"""CPU per coupled step of the double-wishbone corner model alone (no bus, no node shell).

    python bench/bench_corner_cpu.py [--steps 1000] [--repeats 5] [--substeps 2]

Each coupled step makes the calls the plant node makes (nodes/plant/node.py):
``spring_force``, ``extra_response``, ``response_velocities`` before and after the first
substep, ``loads``, and ``state`` after every substep, with constant forces (the static tyre
load, no damper force). Prints the best of ``--repeats`` runs of ``--steps`` steps in
``time.process_time`` (CPU of this process) per step [us]: the figure docs/cosim.md's
issue #16 section quotes.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def one_step(model, dt: float, n_sub: int, F_t: np.ndarray, F_d: np.ndarray) -> None:
    """One coupled step of the plant node's calls on ``model``."""
    model.spring_force()
    model.extra_response()
    model.response_velocities()
    model.substep(dt, F_t, F_d)
    model.state()
    model.response_velocities()
    model.loads()
    for _ in range(1, n_sub):
        model.substep(dt, F_t, F_d)
        model.state()


def main() -> int:
    from nodes.plant.double_wishbone import DoubleWishboneCorner

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--substeps", type=int, default=2)
    ap.add_argument("--h", type=float, default=0.0005, help="coupled step [s]")
    args = ap.parse_args()
    model = DoubleWishboneCorner()
    try:
        dt = args.h / args.substeps
        F_t, F_d = model.static_tyre_load(), np.zeros(1)
        for _ in range(50):  # warm up
            one_step(model, dt, args.substeps, F_t, F_d)
        best = []
        for _ in range(args.repeats):
            t0 = time.process_time()
            for _ in range(args.steps):
                one_step(model, dt, args.substeps, F_t, F_d)
            best.append((time.process_time() - t0) / args.steps * 1e6)
    finally:
        model.close()
    print(f"double-wishbone corner, {args.substeps} substeps: best {min(best):.0f} us of CPU "
          f"per coupled step (runs: {', '.join(f'{b:.0f}' for b in best)})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
