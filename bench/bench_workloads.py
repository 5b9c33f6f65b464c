"""The workloads side by side: coupled steps/s, CPU per step and peak RSS of every process, and
the ratio to the bare Zenoh round-trip rate measured in the same bench run (issue #16); and
every row of issue #28's table in one command, with its bar.

    python bench/bench_workloads.py [--repeats 2] [--t-end 4] [--rows null,lumped,...]

``--rows`` (default ``null,lumped,corner_fatigue,corner,full``; ``sweep`` on request: it takes
minutes): ``null`` is bench/bench_null_chain.py's 5-process sequential chain, raw and through
the protocol, measured in the same run, and their ratio (bar >= 0.6); ``lumped`` the Ch 3
quarter car (bar >= 3000 steps/s); ``corner_fatigue`` the realistic corner with live fatigue
(bar >= 1600; CPU per step per process, fatigue <= 100 us); ``corner`` the same without
fatigue; ``full`` the 7-DOF vehicle; ``sweep`` the wall time of ``suscosim sweep
scenarios/thesis/ch6_fatigue.toml`` (bar < 240 s). The load average is printed with each row.

Workloads: the lumped quarter car (Ch 3, h = 1 ms), the realistic double-wishbone corner
(Ch 6 base scenario, h = 0.5 ms) with the live fatigue node on and off, and the 7-DOF full
vehicle (Ch 4, h = 2 ms). The live fatigue node needs the lower arm's joint loads, which only
the double-wishbone corner publishes, so it is "n/a" for the other two.

Per process: CPU (user + system, from /proc/PID/stat, sampled every 50 ms until the process
ends) per coupled step with the start-up removed (a run of a quarter of the length is
subtracted: imports and the FE cache load cost 0.3-1 s of CPU), and peak RSS (VmHWM).
"round trips/s" is 1 / the bare two-process Zenoh ping-pong round trip
(callback subscriber, low-latency transport, express: the options of the embedded mesh), and
"ratio" the coupled steps/s over it. Wall-clock numbers depend on what else the 2 cores do:
run it on a quiet machine.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

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
    """(raw, protocol) steps/s of bench/bench_null_chain.py's 5-process sequential chain,
    medians of ``repeats``, measured in one run of it."""
    out = subprocess.run([sys.executable, str(ROOT / "bench" / "bench_null_chain.py"),
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


def main() -> int:
    from bench_zenoh_pingpong import one as pingpong

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--t-end", type=float, default=4.0, help="simulated seconds per run")
    ap.add_argument("--rows", default="null,lumped,corner_fatigue,corner,full",
                    help=f"rows of issue #28's table, of {','.join(ROWS)}")
    ap.add_argument("--null-steps", type=int, default=3000)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="a scenario override for every workload run (e.g. "
                         "'fatigue.influence=\"builtin:structured\"': the hand-meshed arm "
                         "#28's fatigue bar was set on)")
    ap.add_argument("--lowlatency", action=argparse.BooleanOptionalAction, default=None,
                    help="the nodes' transport (suscosim run --lowlatency/--no-lowlatency; "
                         "default: the run's own, universal nodes)")
    args = ap.parse_args()
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


if __name__ == "__main__":
    raise SystemExit(main())
