"""Whole runs: coupled steps/s, CPU per step and peak RSS of the workloads, the Chapter 3 run's
throughput, and the corner model's CPU per step alone. Wall-clock numbers depend on what else
the cores do: run them on a quiet machine; timing is measured here, never asserted in tests.

    python -m bench workloads [--repeats 2] [--t-end 4] [--rows null,lumped,...] [--set K=V]
    python -m bench throughput [--repeats 3] [--t-end 8] [--pin auto|on|off] [--lowlatency]
                               [--exchange sequential|parallel]
    python -m bench corner-cpu [--steps 1000] [--repeats 5] [--substeps 2] [--h 0.0005]
    python -m bench fatigue [--equivalent signed_von_mises] [--method strain_life]
    python -m bench fatigue --run RUN_DIR [--screen 0.01] [--repeat 3]

``workloads`` (issues #16 and #28): every row of issue #28's table with its bar. ``--rows``
(default ``null,lumped,corner_fatigue,corner,full``; ``sweep`` on request, it takes minutes):
``null`` the null chain's 5-process sequential chain (``python -m bench null-chain``), raw and
through the protocol, and their ratio (bar >= 0.6); ``lumped`` the Ch 3 quarter car (h 1 ms,
bar >= 3000 steps/s); ``corner_fatigue`` the realistic corner (Ch 6, h 0.5 ms) with live
fatigue (bar >= 1600); ``corner`` the same without; ``full`` the 7-DOF vehicle (Ch 4, h 2 ms;
live fatigue is n/a for the lumped and 7-DOF models: no lower-arm joint loads); ``sweep`` the
wall time of ``suscosim sweep scenarios/thesis/ch6_fatigue.toml`` (bar < 240 s). Per process:
CPU (user + system, /proc/PID/stat every 50 ms) per coupled step with the start-up removed (a
run a quarter as long subtracted) and peak RSS (VmHWM); "ratio" is the steps/s over the bare
two-process Zenoh round-trip rate (bench/bench_zenoh_pingpong.py: callback subscriber,
low-latency, express) measured in the same bench run. The load average is printed per row.

``throughput``: the distributed Chapter 3 run (four node processes over Zenoh on loopback,
h = 1 ms), both exchange orders: summary.json's steps/s (from ``start`` to the last coupled
node's ``done``), the same with the recorder's table export, and CPU per coupled step of all
processes (user + system, start-up subtracted; the steadier number).

``corner-cpu``: CPU per coupled step of the double-wishbone corner model alone (no bus, no node
shell): the calls the plant node makes (``spring_force``, ``extra_response``,
``response_velocities`` before and after the first substep, ``loads``, ``state`` after every
substep) with constant forces (the static tyre load, no damper force); the best of
``--repeats`` runs of ``--steps`` steps in ``time.process_time`` [us] (docs/cosim.md, issue #16).

``fatigue``: throughput of the fatigue chain in node-samples per second: a synthetic 37 s x 500
Hz load history (the thesis's pavé track length in time) on the default built-in arm, all
surface nodes: superposition, equivalent stress, rainflow, Miner. ``--run``: CPU time
(process_time, not wall) per coupled step of the live engine fed a run's recorded ``plant/arm``
loads in blocks of ``fatigue.block_samples`` as the live node does (e.g. a Ch 6 realistic-corner
run folder), unscreened and with ``--screen`` f (``--screen 0``: unscreened only); every
repeat's damage, extremes, ranges and cycle counts are checked ``array_equal`` to the first's
(the numpy oracles the tests compare the engine with are in
``tests/fatigue/oracle_turning_eq.py``, not a product path). The numba kernels are compiled (or
loaded from their cache) by ``worker.warm_up()`` before the clock starts (as the live node does
before it is ready): the time is printed.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

# ---- workloads ------------------------------------------------------------------------------
WORKLOADS = [
    ("lumped", "lumped quarter car (ch3, h 1 ms)", "scenarios/ch3_step_quarter_car.toml", None),
    ("corner_fatigue", "realistic corner + live fatigue (ch6, h 0.5 ms)",
     "scenarios/thesis/ch6_realistic_qvm.toml", True),
    ("corner", "realistic corner, no fatigue (ch6, h 0.5 ms)",
     "scenarios/thesis/ch6_realistic_qvm.toml", False),
    ("full", "7-DOF full vehicle (ch4, h 2 ms)", "scenarios/ch4_fvm_random.toml", None),
]
BARS = {"lumped": 3000.0, "corner_fatigue": 1600.0}
"""Issue #28's bars [coupled steps/s, quiet 2-core machine]."""
ROWS = ("null", "lumped", "corner_fatigue", "corner", "full", "sweep")
TICK = os.sysconf("SC_CLK_TCK")


def _descendants(root: int) -> list[int]:
    """PIDs of every process below ``root`` (by parent PID, from /proc)."""
    parent: dict[int, int] = {}
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                parent[int(d.name)] = int((d / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                pass
    out, todo = [], [root]
    while todo:
        p = todo.pop()
        kids = [c for c, pp in parent.items() if pp == p]
        out += kids
        todo += kids
    return out


def _sample(pid: int) -> tuple[str, float, int] | None:
    """(name, cpu seconds, peak RSS bytes) of a live process."""
    try:
        cmd = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
        stat = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return None
    args = [a.decode(errors="replace") for a in cmd if a]
    if "node" in args:
        name = args[args.index("node") + 1]
    elif "run" in args:
        name = "orchestrator"
    else:
        return None
    cpu = (int(stat[11]) + int(stat[12])) / TICK
    hwm = next((int(line.split()[1]) * 1024 for line in status.splitlines()
                if line.startswith("VmHWM:")), 0)
    return name, cpu, hwm


SETS: list[str] = []
"""``--set`` overrides for every run (``--set`` of this bench)."""

RUN_ARGS: list[str] = []
"""Options of ``suscosim run`` for every run (``--[no-]lowlatency`` of this bench)."""


def one_run(scenario: str, fatigue: bool | None, t_end: float) -> dict:
    """Run once; steps/s from summary.json and per-process CPU / peak RSS."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "orchestrator", "run", str(ROOT / scenario), "--out", tmp,
               "--quiet", "--set", f"run.t_end={t_end}"]
        for kv in SETS:
            cmd += ["--set", kv]
        cmd += RUN_ARGS
        if fatigue is not None:
            cmd += ["--set", f"fatigue.live={'true' if fatigue else 'false'}"]
        proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, env=dict(os.environ, PYTHONPATH=str(ROOT)))
        last: dict[int, tuple[str, float, int]] = {}
        while proc.poll() is None:
            for pid in [proc.pid, *_descendants(proc.pid)]:
                s = _sample(pid)
                if s is not None:
                    last[pid] = s
            time.sleep(0.05)
        err = proc.stderr.read().decode() if proc.stderr else ""
        summary = json.loads((Path(tmp) / "summary.json").read_text())
    if summary.get("status") != "ok":
        raise RuntimeError(f"{scenario}: run {summary.get('status')}: {err[-400:]}")
    per: dict[str, dict[str, float]] = {}
    for name, cpu, hwm in last.values():
        per[name] = {"cpu_s": cpu, "peak_rss_mb": hwm / 2**20}
    return {"steps_per_s": float(summary["steps_per_s"]), "n_steps": int(summary["n_steps"]),
            "per": per}


def marginal_cpu_us(long: dict, short: dict) -> dict[str, float]:
    """CPU per coupled step of each process [us], start-up removed: the difference between a
    long and a short run over the difference of their steps."""
    dn = long["n_steps"] - short["n_steps"]
    return {n: (long["per"][n]["cpu_s"] - short["per"].get(n, {"cpu_s": 0.0})["cpu_s"]) / dn * 1e6
            for n in long["per"]}


def _load() -> str:
    return Path("/proc/loadavg").read_text().split()[0]


def null_chain(repeats: int, steps: int) -> tuple[float, float]:
    """(raw, protocol) steps/s of ``null-chain``'s 5-process sequential chain,
    medians of ``repeats``, measured in one run of it."""
    out = subprocess.run([sys.executable, "-m", "bench.null_chain", "null-chain",
                          "--counts", "5", "--exchanges", "sequential", "--wires",
                          "raw,protocol", "--repeats", str(repeats), "--steps", str(steps),
                          "--pingpong-n", "300"], cwd=ROOT, capture_output=True, text=True,
                         check=True).stdout
    rates = {}
    for line in out.splitlines():
        for wire in ("raw", "protocol"):
            head = f"5 processes, {wire}, sequential: "
            if line.strip().startswith(head):
                rates[wire] = float(line.strip()[len(head):].split()[0])
    return rates["raw"], rates["protocol"]


def sweep_wall_s() -> float:
    """Wall time of the Chapter 6 sweep (16 runs, live fatigue) [s]. A failed sweep's folder
    is kept (its failed points' logs say why) and named on stderr."""
    tmp = tempfile.mkdtemp(prefix="bench-sweep-")
    t0 = time.monotonic()
    code = subprocess.run([sys.executable, "-m", "orchestrator", "sweep",
                           str(ROOT / "scenarios/thesis/ch6_fatigue.toml"), "--out", tmp],
                          cwd=ROOT, stdout=subprocess.DEVNULL,
                          env=dict(os.environ, PYTHONPATH=str(ROOT))).returncode
    wall = time.monotonic() - t0
    if code != 0:
        raise SystemExit(f"the sweep failed (exit {code}) after {wall:.0f} s: its folder, "
                         f"with the failed points' run folders and logs, is kept in {tmp}")
    shutil.rmtree(tmp, ignore_errors=True)
    return wall


def workloads(args: argparse.Namespace) -> int:
    """``workloads``: issue #28's table."""
    from bench.bench_zenoh_pingpong import one as pingpong

    SETS[:] = args.set
    RUN_ARGS[:] = [] if args.lowlatency is None else \
        ["--lowlatency" if args.lowlatency else "--no-lowlatency"]
    rows = [r for r in args.rows.split(",") if r]
    bad = [r for r in rows if r not in ROWS]
    if bad:
        print(f"--rows: unknown {', '.join(bad)} (of {', '.join(ROWS)})", file=sys.stderr)
        return 2
    print(f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {os.cpu_count()} CPUs, "
          f"load {_load()}" + (f", --set {' '.join(SETS)}" if SETS else "")
          + "".join(f" {a}" for a in RUN_ARGS) + "\n")
    if "null" in rows:
        raw, proto = null_chain(args.repeats, args.null_steps)
        print(f"null chain, 5 processes, sequential: raw {raw:.0f}, protocol {proto:.0f} "
              f"steps/s; protocol/raw {proto / raw:.2f} (bar >= 0.6; load {_load()})\n")
    rate = 0.0
    if any(r in rows for r, *_ in WORKLOADS):
        rtts = [pingpong(2000, fifo=False, ll=True, express=True)["rtt_us"] for _ in range(2)]
        rtt = statistics.median(rtts)
        rate = 1e6 / rtt
        print(f"bare Zenoh round trip: {rtt:.0f} us ({rate:.0f} round trips/s), "
              f"median of {len(rtts)}\n")
        print("| workload | coupled steps/s | bar | ratio to round trips/s | CPU per step per "
              "process (us) | peak RSS per process (MB) | load |")
        print("|---|---|---|---|---|---|---|")
    for key, label, scenario, fatigue in WORKLOADS:
        if key not in rows:
            continue
        runs = [one_run(scenario, fatigue, args.t_end) for _ in range(args.repeats)]
        sps = statistics.median(r["steps_per_s"] for r in runs)
        best = max(runs, key=lambda r: r["steps_per_s"])
        short = one_run(scenario, fatigue, args.t_end / 4)
        per_step = marginal_cpu_us(best, short)
        names = sorted(best["per"])
        cpu = ", ".join(f"{n} {per_step[n]:.0f}" for n in names)
        rss = ", ".join(f"{n} {best['per'][n]['peak_rss_mb']:.0f}" for n in names)
        each = ", ".join(f"{r['steps_per_s']:.0f}" for r in runs)
        bar = f">= {BARS[key]:.0f}" if key in BARS else ""
        print(f"| {label} | {sps:.0f} ({each}) | {bar} "
              f"| {sps / rate:.2f} | {cpu} | {rss} | {_load()} |", flush=True)
    if "sweep" in rows:
        print(f"\nsuscosim sweep scenarios/thesis/ch6_fatigue.toml: {sweep_wall_s():.0f} s "
              f"(bar < 240 s; load {_load()})")
    print("\nlive fatigue: n/a for the lumped and 7-DOF models (no lower-arm joint loads)")
    return 0


# ---- throughput -----------------------------------------------------------------------------
SCENARIO = ROOT / "scenarios" / "ch3_step_quarter_car.toml"


def throughput_run(t_end: float, exchange: str, extra: list[str]) -> tuple[float, float, float]:
    """(steps/s, steps/s incl. the export, CPU seconds of the whole run incl. every node)."""
    with tempfile.TemporaryDirectory() as tmp:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run([sys.executable, "-m", "orchestrator", "run", str(SCENARIO), "--out",
                        tmp, "--quiet", "--set", f"run.t_end={t_end}",
                        "--set", f'run.exchange="{exchange}"', *extra],
                       cwd=ROOT, check=True, capture_output=True,
                       env=dict(os.environ, PYTHONPATH=str(ROOT)))
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        summary = json.loads((Path(tmp) / "summary.json").read_text())
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    with_export = summary["n_steps"] / summary["run_wall_s"]
    return float(summary["steps_per_s"]), with_export, cpu


def throughput(args: argparse.Namespace) -> int:
    """``throughput``: steps/s and CPU per step of the distributed Chapter 3 run."""
    extra = ([] if args.lowlatency is None else
             ["--lowlatency" if args.lowlatency else "--no-lowlatency"]) + ["--pin", args.pin]
    _, _, cpu0 = throughput_run(0.001, "sequential", extra)  # start-up: imports, sessions, barrier
    n = round(args.t_end / 0.001)
    load = os.getloadavg()[0]
    print(f"load average at start: {load:.1f}; startup CPU {cpu0:.2f} s")
    print("| exchange | steps/s (median) | steps/s (all runs) | incl. export (median) "
          "| CPU per step (ms) |")
    print("|---|---|---|---|---|")
    for exchange in args.exchange or ("sequential", "parallel"):
        rates, exported, cpus = [], [], []
        for _ in range(args.repeats):
            r, e, c = throughput_run(args.t_end, exchange, extra)
            rates.append(r)
            exported.append(e)
            cpus.append((c - cpu0) / n * 1e3)
        print(f"| {exchange} | {statistics.median(rates):.0f} | "
              f"{', '.join(f'{r:.0f}' for r in rates)} | {statistics.median(exported):.0f} | "
              f"{statistics.median(cpus):.2f} |", flush=True)
    print(f"load average at end: {os.getloadavg()[0]:.1f}")
    return 0


# ---- corner-cpu -----------------------------------------------------------------------------
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


def corner_cpu(args: argparse.Namespace) -> int:
    """``corner-cpu``: the corner model's CPU per coupled step."""
    from nodes.plant.double_wishbone import DoubleWishboneCorner

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


# ---- fatigue --------------------------------------------------------------------------------
def fatigue(a: argparse.Namespace) -> int:
    """``fatigue``: the chain's node-samples per second, or the live engine's CPU per step."""
    t_import = time.perf_counter()
    from nodes.fatigue import worker  # the numba kernels compile or load here
    from nodes.fatigue.config import FatigueConfig
    from nodes.fatigue.synthetic import pave_like_loads
    from nodes.fatigue.worker import analyse, load_influence

    t_import = time.perf_counter() - t_import
    if a.run:
        from nodes.fatigue.lib import counting

        t0 = time.perf_counter()
        worker.warm_up()
        print(f"import of the worker {t_import:.2f} s, warm_up {time.perf_counter() - t0:.2f}"
              f" s wall (numba kernels, compiled or from the cache: {counting.COMPILE_S})")
        first: dict = {}
        for _ in range(a.repeat):
            _fatigue_live_cpu(a.run, a.screen, first)
        return 0
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
    return 0


def _fatigue_live_cpu(run: str, screen: float, first: dict) -> None:
    """The live engine's CPU per step on a run's recorded loads (``fatigue --run``)."""
    from nodes.fatigue.config import FatigueConfig
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


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("workloads", help="issue #28's table: steps/s, CPU, RSS, bars")
    p.add_argument("--repeats", type=int, default=2)
    p.add_argument("--t-end", type=float, default=4.0, help="simulated seconds per run")
    p.add_argument("--rows", default="null,lumped,corner_fatigue,corner,full",
                   help=f"rows of issue #28's table, of {','.join(ROWS)}")
    p.add_argument("--null-steps", type=int, default=3000)
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="a scenario override for every workload run (e.g. "
                        "'fatigue.mesh_size_m=0.03')")
    p.add_argument("--lowlatency", action=argparse.BooleanOptionalAction, default=None,
                   help="the nodes' transport (suscosim run --lowlatency/--no-lowlatency; "
                        "default: the run's own, universal nodes)")
    p.set_defaults(fn=workloads)
    p = sub.add_parser("throughput", help="steps/s and CPU per step of the Chapter 3 run")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--t-end", type=float, default=8.0)
    p.add_argument("--lowlatency", action=argparse.BooleanOptionalAction, default=None,
                   help="Zenoh's low-latency transport (suscosim run --lowlatency; default: "
                        "the run's default, universal since it could wedge a start)")
    p.add_argument("--pin", choices=["auto", "on", "off"], default="auto",
                   help="CPU placement of the node processes (suscosim run --pin)")
    p.add_argument("--exchange", choices=["sequential", "parallel"], action="append",
                   help="exchange order(s) to measure (default both)")
    p.set_defaults(fn=throughput)
    p = sub.add_parser("corner-cpu", help="the corner model's CPU per coupled step")
    p.add_argument("--steps", type=int, default=1000)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--substeps", type=int, default=2)
    p.add_argument("--h", type=float, default=0.0005, help="coupled step [s]")
    p.set_defaults(fn=corner_cpu)
    p = sub.add_parser("fatigue", help="the fatigue chain's node-samples/s; live CPU per step")
    p.add_argument("--equivalent", default="abs_max_principal")
    p.add_argument("--method", default="stress_life")
    p.add_argument("--mean-stress", default="goodman")
    p.add_argument("--nodes", default="surface")
    p.add_argument("--run", default=None, help="a run folder: live engine CPU per step")
    p.add_argument("--screen", type=float, default=0.01)
    p.add_argument("--repeat", type=int, default=1, help="repeats (--run)")
    p.set_defaults(fn=fatigue)
    args = ap.parse_args(argv)
    return int(args.fn(args) or 0)


if __name__ == "__main__":
    raise SystemExit(main())
