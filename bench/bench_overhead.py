"""What the co-simulation costs over the same work in one process (issue #41): per workload,
the coupled steps/s of the distributed run (a process per node over Zenoh), the steps/s of
the one-process engine (``--inprocess``: the same node models, one thread, no bus,
orchestrator/inprocess.py) and their ratio (distributed / in-process), the bare Zenoh round
trip and the load average, all in one run of this script, so that the ratios compare runs on
the same machine under the same load. ``--trace`` adds one traced distributed run of each row
but ``lumped`` (:func:`step_trace`): the median timeline of a coupled step.

    python bench/bench_overhead.py [--json] [--repeats 1] [--rows lumped,corner,...] [--trace]

Workloads (bench/workloads.py's): ``lumped`` the Ch 3 quarter car (h 1 ms), ``corner`` the Ch
6 realistic corner (h 0.5 ms) without live fatigue, ``corner_fatigue`` with it, ``full`` the
7-DOF vehicle (Ch 4, h 2 ms). Each run is a few seconds; the distributed and in-process runs
alternate, and each rate is the median of ``--repeats``. steps/s is summary.json's: from the
start to the last coupled step (the distributed run's sinks go on in parallel; the engine's
sinks are in its one thread). The round trip is bench/bench_zenoh_pingpong.py's (callback
subscriber, low-latency, express). ``--json`` prints one JSON object on its last line:
``{"lumped": {"coupled_steps_s", "inprocess_steps_s", "ratio", "inprocess_chain_steps_s",
"ratio_to_chain", "inprocess_cpu_steps_s"}, ..., "zenoh_rtt_us", "load"}``. The chain's rate
is the engine's with the time its sinks (recorder, live fatigue) took removed (summary.json
``inprocess``): the distributed run's sinks work on other cores. On a shared machine
wall-clock rates favour the distributed run (the scheduler gives each of its 5 processes a
share, the engine's one process one share): the in-process steps per second of CPU time is
the engine's work alone. Timing is measured here, never asserted in tests.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

T_END = {"lumped": 3.0, "corner": 1.0, "corner_fatigue": 1.0, "full": 2.0}
"""Simulated time per workload [s]: 1.5-3 s of wall time each on this machine."""


def load_average() -> float:
    return float(Path("/proc/loadavg").read_text().split()[0])


def steps_per_s(scenario: str, fatigue: bool | None, t_end: float,
                inprocess: bool) -> tuple[float, float, float]:
    """summary.json's steps/s of one run, and (in-process) the chain's alone (its sinks'
    time taken out: what the distributed run does on other cores) and the steps per second
    of the engine's CPU time (the work, whatever else the machine runs)."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "orchestrator", "run", str(ROOT / scenario), "--out", tmp,
               "--quiet", "--set", f"run.t_end={t_end}",
               *(["--inprocess"] if inprocess else ["--mode", "distributed"])]
        if fatigue is not None:
            cmd += ["--set", f"fatigue.live={'true' if fatigue else 'false'}"]
        res = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True,
                             env=dict(os.environ, PYTHONPATH=str(ROOT)))
        if res.returncode != 0:
            raise SystemExit(f"{scenario} ({'in-process' if inprocess else 'distributed'}): "
                             f"exit {res.returncode}: {res.stderr[-400:]}")
        summary = json.loads((Path(tmp) / "summary.json").read_text())
        inp = summary.get("inprocess") or {}
        cpu = float(inp.get("step_cpu_s", 0.0))
        return (float(summary["steps_per_s"]), float(inp.get("chain_steps_per_s", 0.0)),
                summary["n_steps"] / cpu if cpu > 0 else 0.0)


_TRACE_HOOK = r'''
import os, time
if os.environ.get("SUSCOSIM_STEP_TRACE"):  # bench_overhead --trace: a timestamp at each
    import json                             # wait's end and each step message's put
    from cosim import outbox, participant
    _clock, _waits, _puts = time.perf_counter, [], []
    _wait, _send, _finish = (participant.Participant.wait, outbox.Outbox.send,
                             participant.Participant.finish)

    def wait(self, needs):
        got = _wait(self, needs)
        _waits.append((max(needs.values()), _clock()))
        return got

    def send(self, held=False):
        k, sends = self._step_kt[0], bool(self._step or (held and self._held))
        t0 = _clock()
        _send(self, held)
        if sends:
            _puts.append((k, t0, _clock()))

    def finish(self, *a, **kw):
        with open(os.path.join(os.environ["SUSCOSIM_STEP_TRACE"], self.node + ".json"), "w") as f:
            json.dump({"waits": _waits, "puts": _puts}, f)
        return _finish(self, *a, **kw)

    participant.Participant.wait, participant.Participant.finish = wait, finish
    outbox.Outbox.send = send
'''

TRACED = ("plant", "tyre_road", "controller")


def step_trace(scenario: str, fatigue: bool | None, t_end: float) -> dict[str, float]:
    """One distributed run with a timestamp at the end of each node's wait for a step and
    around each step message's put (a ``sitecustomize`` on the nodes' path patches
    :class:`cosim.participant.Participant`; no product code is changed): the median of each
    part of a coupled step [us], from the plant's put of state k."""
    import numpy as np

    with tempfile.TemporaryDirectory() as tmp:
        hook = Path(tmp) / "hook"
        hook.mkdir()
        (hook / "sitecustomize.py").write_text(_TRACE_HOOK)
        cmd = [sys.executable, "-m", "orchestrator", "run", str(ROOT / scenario), "--out",
               str(Path(tmp) / "run"), "--quiet", "--set", f"run.t_end={t_end}"]
        if fatigue is not None:
            cmd += ["--set", f"fatigue.live={'true' if fatigue else 'false'}"]
        subprocess.run(cmd, cwd=ROOT, capture_output=True, check=True, env=dict(
            os.environ, PYTHONPATH=f"{hook}{os.pathsep}{ROOT}", SUSCOSIM_STEP_TRACE=tmp))
        tr = {n: json.loads((Path(tmp) / f"{n}.json").read_text()) for n in TRACED}
    got = {n: {int(k): t for k, t in tr[n]["waits"]} for n in TRACED}
    put = {n: {int(k): (t0, t1) for k, t0, t1 in tr[n]["puts"]} for n in TRACED}
    rows = []
    for k in sorted(put["plant"])[200:-2]:  # warm; the plant's step k + 1 put ends step k
        if all(k in got[n] and k in put[n] for n in TRACED) and k + 1 in put["plant"]:
            p0, p1 = put["plant"][k]
            forces = max(put[n][k][1] for n in TRACED[1:])
            rows.append([p1 - p0, *(got[n][k] - p0 for n in TRACED[1:]),
                         *(put[n][k][0] - got[n][k] for n in TRACED[1:]),
                         got["plant"][k] - forces, put["plant"][k + 1][0] - got["plant"][k],
                         put["plant"][k + 1][0] - p0])
    med = np.median(np.array(rows) * 1e6, axis=0)
    names = ("plant's put", "tyre_road has the state", "controller has the state",
             "tyre_road's step", "controller's step", "the plant has the forces after the "
             "last put", "the plant's step to its next put", "a coupled step")
    return dict(zip(names, (float(x) for x in med), strict=True))


def main(argv: list[str] | None = None) -> int:
    from bench.bench_zenoh_pingpong import one as pingpong
    from bench.workloads import WORKLOADS

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="one JSON object on the last line")
    ap.add_argument("--repeats", type=int, default=1, help="runs of each kind per workload")
    ap.add_argument("--rows", default="lumped,corner,corner_fatigue,full")
    ap.add_argument("--trace", action="store_true",
                    help="then one traced distributed run of each row: a step's timeline")
    args = ap.parse_args(argv)
    rows = [r for r in args.rows.split(",") if r]
    known = [w[0] for w in WORKLOADS]
    if args.repeats < 1 or any(r not in known for r in rows):
        print(f"--rows: of {', '.join(known)}; --repeats >= 1", file=sys.stderr)
        return 2
    loads = [load_average()]
    rtt = pingpong(2000, fifo=False, ll=True, express=True)["rtt_us"]
    print(f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {os.cpu_count()} CPUs, "
          f"load {loads[0]:.2f}; bare Zenoh round trip {rtt:.0f} us\n")
    print("| workload | distributed steps/s | in-process steps/s | ratio | in-process chain "
          "steps/s (sinks out) | ratio to the chain | in-process steps per CPU s | load |")
    print("|---|---|---|---|---|---|---|---|")
    out: dict[str, object] = {}
    for key, label, scenario, fatigue in WORKLOADS:
        if key not in rows:
            continue
        dist, inproc, chain, cpu = [], [], [], []
        for _ in range(args.repeats):
            dist.append(steps_per_s(scenario, fatigue, T_END[key], inprocess=False)[0])
            i_all, i_chain, i_cpu = steps_per_s(scenario, fatigue, T_END[key], inprocess=True)
            inproc.append(i_all)
            chain.append(i_chain)
            cpu.append(i_cpu)
        d, i, c = statistics.median(dist), statistics.median(inproc), statistics.median(chain)
        u = statistics.median(cpu)
        loads.append(load_average())
        out[key] = {"coupled_steps_s": round(d, 1), "inprocess_steps_s": round(i, 1),
                    "ratio": round(d / i, 3), "inprocess_chain_steps_s": round(c, 1),
                    "ratio_to_chain": round(d / c, 3) if c > 0 else None,
                    "inprocess_cpu_steps_s": round(u, 1)}
        print(f"| {label} | {d:.0f} | {i:.0f} | {d / i:.2f} | {c:.0f} | "
              f"{d / c if c > 0 else float('nan'):.2f} | {u:.0f} | {loads[-1]:.2f} |",
              flush=True)
    for key, label, scenario, fatigue in WORKLOADS if args.trace else ():
        if key in rows and key != "lumped":  # (the lumped car has no ``controller`` step)
            parts = step_trace(scenario, fatigue, T_END[key])
            out[f"{key}_trace_us"] = {n: round(v, 1) for n, v in parts.items()}
            print(f"\n{label}, median [us] from the start of the plant's put of state k:\n"
                  + "\n".join(f"  {n}: {v:.0f}" for n, v in parts.items()), flush=True)
    out["zenoh_rtt_us"] = round(rtt, 1)
    out["load"] = [round(x, 2) for x in loads]
    if args.json:
        print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
