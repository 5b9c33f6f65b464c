"""The benchmarks: ``python -m bench`` lists them, ``python -m bench NAME [ARGS]`` runs one
(``python -m bench NAME --help``: its options). Run from the repository root. Each module's
docstring says in full what its commands measure; timing is measured here, never asserted in
tests.
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

COMMANDS: dict[str, tuple[str, bool, str]] = {
    # NAME: (module in bench/, NAME is a subcommand of its main, what it measures)
    "pingpong": ("bench_zenoh_pingpong", False,
                 "Zenoh round trip and CPU per round trip between two processes, per option"),
    "overhead": ("bench_overhead", False,
                 "distributed steps/s over the one-process engine's, per workload (#41)"),
    "null-chain": ("null_chain", True,
                   "steps/s of the run's lock-step pattern with zero model work (#16)"),
    "wire": ("protocol", True, "codec, signing and a step's protocol work [us per call] (#28)"),
    "auth": ("protocol", True, "message authentication: per message and steps/s (#15)"),
    "transport": ("transport", True,
                  "steps/s of the Chapter 3 run over loopback, a router, namespaces"),
    "join-stress": ("transport", True, "does a Zenoh session wedge while peers join at once"),
    "tap-overhead": ("transport", True, "a live tap's cost to a run; replay rate into a tap"),
    "workloads": ("workloads", True,
                  "issue #28's table: steps/s, CPU per step, peak RSS of each workload, bars"),
    "throughput": ("workloads", True, "steps/s and CPU per step of the Chapter 3 run"),
    "corner-cpu": ("workloads", True, "CPU per coupled step of the corner model alone"),
    "fatigue": ("workloads", True,
                "fatigue chain node-samples/s; the live engine's CPU per step (--run)"),
    "memory": ("memory", True, "peak RSS and bytes per step of long runs; post-processing (#32)"),
    "tile-table": ("memory", True, "a longer run folder from a shorter one (for memory --post)"),
    "cosim": ("accuracy", True,
              "Tables 3.2, 3.3: wall time and peak error per communication step"),
    "coupling": ("accuracy", True, "peak error per coupling mode and exchange order"),
    "coupling-residual": ("accuracy", True, "the coupling's energy residual beside the error"),
    "adaptive-step": ("accuracy", True, "run.h = 'auto' against fixed steps: steps and error"),
    "roll-budget": ("accuracy", True,
                    "where the 0.5 g corner's roll departs from the hand formula (#44)"),
    "arm-cad-grid": ("arm_studies", True, "which CAD variants of the arm OCC can fillet"),
    "arm-fillet-order": ("arm_studies", True, "which fillets OCC accepts, in which order"),
    "arm-variant": ("arm_studies", True, "one CAD variant through the part card's FE"),
    "arm-convergence": ("arm_studies", True, "the built-in arm's mesh-convergence table"),
    "upper-arm-cad": ("arm_studies", True, "make the upper wishbone's STEP (and its card)"),
    "ch5-compare": ("thesis_ch5", True, "Table 5.3: a Chapter 5 sweep's ride metrics by law"),
    "ch5-pave-tables": ("thesis_ch5", True, "Tables 5.6-5.11 of the full-vehicle pavé sweep"),
    "ch5-sine-study": ("thesis_ch5", True, "Figs 5.11-5.17: the laws under road sinusoids"),
    "ch5-sine-bounds": ("thesis_ch5", True, "closed-form bounds behind the sine study's misses"),
    "calibrate-pave": ("thesis_ch6", True, "the synthetic pavé's ride RMS against Table 4.5"),
    "ch6-results": ("thesis_ch6", True, "Tables 6.3-6.6: the arm's lives from a ch6_fatigue sweep"),
    "ch6-sensitivity": ("thesis_ch6", True, "the Chapter 6 sweep by node, notch and method"),
}


def _present(module: str) -> bool:
    return (HERE / f"{module}.py").is_file()


def listing() -> str:
    """NAME and what it measures, by module."""
    lines = ["python -m bench NAME [ARGS] (NAME --help: its options); from the repository root",
             ""]
    width = max(map(len, COMMANDS))
    module = ""
    for name, (mod, _, what) in COMMANDS.items():
        if not _present(mod):
            continue
        if mod != module:
            lines.append(f"bench/{mod}.py")
            module = mod
        lines.append(f"  {name:<{width}}  {what}")
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    if not argv or argv[0] in ("-h", "--help", "list"):
        print(listing())
        return 0
    name, rest = argv[0], argv[1:]
    if name not in COMMANDS:
        print(f"python -m bench: no benchmark {name!r}\n\n{listing()}", file=sys.stderr)
        return 2
    mod, sub, _ = COMMANDS[name]
    if not _present(mod):
        print(f"python -m bench {name}: bench/{mod}.py is not there", file=sys.stderr)
        return 2
    root = str(HERE.parent)
    if root not in sys.path:
        sys.path.insert(0, root)
    main_fn = importlib.import_module(f"bench.{mod}").main
    # each module's main parses sys.argv: its usage reads "python -m bench NAME ..."
    sys.argv = ["python -m bench", name, *rest] if sub else [f"python -m bench {name}", *rest]
    return int(main_fn() or 0)


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
