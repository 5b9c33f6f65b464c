"""What the co-simulation costs over the same work in one process (issue #41): per workload,
the coupled steps/s of the distributed run (a process per node over Zenoh), the steps/s of
the one-process engine (``--inprocess``: the same node models, one thread, no bus,
orchestrator/inprocess.py) and their ratio (distributed / in-process), the bare Zenoh round
trip and the load average, all in one run of this script, so that the ratios compare runs on
the same machine under the same load. ``--trace`` adds one traced distributed run of each row
but ``lumped`` (:func:`step_trace`): the median timeline of a coupled step.

    python bench/bench_overhead.py [--json] [--repeats 1] [--rows lumped,corner,...] [--trace]
                                   [--helics] [--sched]

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
the engine's work alone. ``--helics`` (``pip install -e ".[bench]"``): the lumped car as 4
HELICS federates (:func:`helics_split`), its steps/s over each HELICS core and the distributed
lumped run's rate over the best (issue #41's goal: >= 5), its last row checked bit for bit
against the one-process run with the same zero-order hold. ``--sched`` (root): each core's
time per coupled step by node and thread from the kernel's scheduler events
(:func:`sched_profile`). Timing is measured here, never asserted in tests.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path
from typing import Any, cast

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

T_END = {"lumped": 3.0, "corner": 1.0, "corner_fatigue": 1.0, "full": 2.0}
"""Simulated time per workload [s]: 1.5-3 s of wall time each on this machine."""


def run_command(scenario: str, fatigue: bool | None, t_end: float, out: str | Path,
                *extra: str) -> list[str]:
    """``suscosim run`` of ``scenario`` for ``t_end`` [s] into ``out`` (``fatigue``: live
    fatigue on/off, None: the scenario's), with ``extra`` arguments."""
    cmd = [sys.executable, "-m", "orchestrator", "run", str(ROOT / scenario), "--out", str(out),
           "--quiet", "--set", f"run.t_end={t_end}", *extra]
    if fatigue is not None:
        cmd += ["--set", f"fatigue.live={'true' if fatigue else 'false'}"]
    return cmd


def load_average() -> float:
    return float(Path("/proc/loadavg").read_text().split()[0])


def steps_per_s(scenario: str, fatigue: bool | None, t_end: float,
                inprocess: bool) -> tuple[float, float, float]:
    """summary.json's steps/s of one run, and (in-process) the chain's alone (its sinks'
    time taken out: what the distributed run does on other cores) and the steps per second
    of the engine's CPU time (the work, whatever else the machine runs)."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = run_command(scenario, fatigue, t_end, tmp,
                          *(["--inprocess"] if inprocess else ["--mode", "distributed"]))
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
        cmd = run_command(scenario, fatigue, t_end, Path(tmp) / "run")
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


_HELICS_FEDERATE = r'''
import json, sys, time
import helics as h
import numpy as np

o = json.loads(sys.argv[1])
role, H, n, eps = o["role"], o["h"], o["n"], o["h"] / 10
fi = h.helicsCreateFederateInfo()
h.helicsFederateInfoSetCoreTypeFromString(fi, o["core"])
h.helicsFederateInfoSetCoreInitString(fi, "--federates=1")
h.helicsFederateInfoSetFlagOption(fi, h.HELICS_FLAG_UNINTERRUPTIBLE, True)
fed = h.helicsCreateValueFederate(role, fi)
def pub(key):
    return h.helicsFederateRegisterGlobalPublication(fed, key, h.HELICS_DATA_TYPE_VECTOR, "")
def sub(key):
    return h.helicsFederateRegisterSubscription(fed, key, "")
if role == "plant":
    from nodes.plant.quarter_car_lumped import LumpedQuarterCar, LumpedQuarterCarParams
    car = LumpedQuarterCar(LumpedQuarterCarParams(**o["vehicle"]))
    out, ins = pub("plant/state"), [sub("tyre_road/force"), sub("controller/force")]
elif role == "tyre_road":
    from nodes.tyre_road.tyres import point_contact_force
    out, ins = pub("tyre_road/force"), [sub("plant/state")]
elif role == "controller":
    out, ins = pub("controller/force"), [sub("plant/state")]
else:
    out, ins = None, [sub("plant/state"), sub("tyre_road/force"), sub("controller/force")]
h.helicsFederateEnterExecutingMode(fed)
last, t0 = None, time.perf_counter()
for k in range(n):
    t = k * H
    if role == "plant":  # state at t_k; the forces at t_k + 2 eps; the substeps to t_k+1
        h.helicsFederateRequestTime(fed, t)
        st = car.state()
        h.helicsPublicationPublishVector(out, [float(st[c][0]) for c in ("z_b", "v_b", "z_w",
                                                                         "v_w")])
        h.helicsFederateRequestTime(fed, t + 2 * eps)
        f_t, f_d = (h.helicsInputGetVector(i)[0] for i in ins)
        for _ in range(o["substeps"]):
            car.substep(H / o["substeps"], np.array((f_t,)), np.array((f_d,)))
        continue
    h.helicsFederateRequestTime(fed, t + (3 if out is None else 1) * eps)
    z_b, v_b, z_w, v_w = h.helicsInputGetVector(ins[0])
    if role == "tyre_road":  # the step road, the point-contact tyre
        z_g = o["height"] if t >= o["t_start"] else 0.0
        h.helicsPublicationPublishVector(out, [float(point_contact_force(
            z_w, z_g, o["k_t"], o["static"])[0])])
    elif role == "controller":  # the passive damper
        h.helicsPublicationPublishVector(out, [-o["c"] * (v_b - v_w)])
    else:
        last = (t, z_b, z_w, *(h.helicsInputGetVector(i)[0] for i in ins[1:]))
wall = time.perf_counter() - t0
h.helicsFederateDisconnect(fed)
if last is not None:
    print(json.dumps({"steps_per_s": n / wall, "last": last}))
'''


def helics_split(t_end: float, core: str = "zmq") -> dict[str, Any]:
    """The Ch 3 lumped car split into 4 HELICS federates (plant, tyre/road, controller,
    recorder; ``pip install helics``), one process each and a broker in this one, exchanging
    sequentially as suscosim's run does: the plant publishes the state at t_k, the force
    federates answer at t_k + h/10, the plant takes the forces at t_k + h/5 and integrates 4
    substeps to t_k+1 (``LumpedQuarterCar``, the point-contact tyre and the passive damper of
    scenarios/ch3_step_quarter_car.toml; zero-order hold); uninterruptible time grants. The
    recorder's steps/s (from executing mode to its last step) and its last row (t, z_b, z_w,
    F_t, F_d), to check the physics against the distributed run's table."""
    import helics as h  # type: ignore[import-untyped]

    sc = tomllib.loads((ROOT / "scenarios/ch3_step_quarter_car.toml").read_text())
    veh = {k: sc["vehicle"][k] for k in ("sprung_mass", "unsprung_mass", "spring_stiffness")}
    base = {"h": sc["run"]["h"], "n": int(round(t_end / sc["run"]["h"])), "core": core,
            "substeps": sc["run"]["substeps"], "vehicle": veh, "k_t": sc["tyre"]["stiffness"],
            "c": sc["controller"]["c"], "height": sc["road"]["height"],
            "t_start": sc["road"]["t_start"],
            "static": (veh["sprung_mass"] + veh["unsprung_mass"]) * 9.81}
    broker = h.helicsCreateBroker(core, "", "-f 4")
    procs = [subprocess.Popen([sys.executable, "-c", _HELICS_FEDERATE,
                               json.dumps(dict(base, role=role))], cwd=ROOT,
                              stdout=subprocess.PIPE, text=True,
                              env=dict(os.environ, PYTHONPATH=str(ROOT)))
             for role in ("plant", "tyre_road", "controller", "recorder")]
    out = procs[-1].communicate(timeout=600)[0]
    for proc in procs:
        proc.wait(timeout=60)
    h.helicsBrokerWaitForDisconnect(broker, 10000)
    return json.loads(out.strip().splitlines()[-1])


def _last_row_of_hold_run(t_end: float) -> list[float]:
    """(t, z_b, z_w, F_t, F_d) of the one-process Ch 3 run with ``coupling = "hold"`` at the
    HELICS split's last step (the split's zero-order hold)."""
    import csv

    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run(run_command("scenarios/ch3_step_quarter_car.toml", None, t_end, tmp,
                                   "--inprocess", "--set", 'run.coupling="hold"'),
                       cwd=ROOT, check=True, capture_output=True)
        with open(Path(tmp) / "table.csv") as f:
            rows = list(csv.DictReader(f))
    row = rows[-2]  # the split's last step is n - 1
    return [float(row[c]) for c in ("t", "plant/state/z_b", "plant/state/z_w",
                                    "tyre_road/force/F_t", "controller/force/F_d")]


TRACEFS = Path("/sys/kernel/tracing")
_SWITCH = re.compile(r"\[(\d+)\]\S*\s+\S+\s+([\d.]+): sched_switch: .*?prev_pid=(\d+) .*"
                     r"next_pid=(\d+) ")


def _tracefs(setting: str, value: str) -> None:
    (TRACEFS / setting).write_text(value)


def _node_pids() -> dict[str, int]:
    """The running ``suscosim node NAME --run ...`` processes: name -> pid."""
    pids = {}
    for proc in Path("/proc").glob("[0-9]*"):
        try:
            argv = (proc / "cmdline").read_bytes().split(b"\0")
            if b"node" in argv and b"--run" in argv:
                pids[argv[argv.index(b"node") + 1].decode()] = int(proc.name)
        except (OSError, ValueError, IndexError):
            continue
    return pids


def _cpu_s(pid: int) -> float:
    """User + system CPU time of process ``pid`` so far [s]."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _stepping(node: str, over_s: float = 0.1) -> bool:
    """Whether node process ``node`` of a run used over half a core for ``over_s``."""
    pid = _node_pids().get(node)
    if pid is None:
        return False
    try:
        before = _cpu_s(pid)
        time.sleep(over_s)
        return _cpu_s(pid) - before > 0.5 * over_s
    except OSError:  # it ended meanwhile
        return False


def sched_profile(scenario: str, fatigue: bool | None, t_end: float,
                  window_s: float = 0.3) -> dict[str, dict[str, float]]:
    """One distributed run with the kernel's ``sched_switch`` events recorded for
    ``window_s`` of its stepping (root and tracefs): each core's time per coupled step [us]
    by node and thread (``main``: its Python threads, ``zenoh``: Zenoh's runtime threads,
    :data:`orchestrator.placement.ZENOH_THREADS`), ``idle`` and ``other`` (other programs,
    the orchestrator). Where a core's time goes, not only how long a step takes."""
    from orchestrator.placement import ZENOH_THREADS

    if not (TRACEFS / "trace").exists():
        subprocess.run(["mount", "-t", "tracefs", "nodev", str(TRACEFS)], check=True)
    _tracefs("tracing_on", "0")
    _tracefs("trace", "")
    _tracefs("buffer_size_kb", "65536")
    _tracefs("events/enable", "0")
    _tracefs("events/sched/sched_switch/enable", "1")
    with tempfile.TemporaryDirectory() as tmp:
        cmd = run_command(scenario, fatigue, t_end, Path(tmp) / "run")
        run = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL,
                               env=dict(os.environ, PYTHONPATH=str(ROOT)))
        while run.poll() is None and not _stepping("plant"):
            time.sleep(0.05)
        time.sleep(1.5)  # past the plant's start-up (its model build keeps it busy too)
        role: dict[int, str] = {}  # thread id -> "node main|zenoh"
        for node, pid in _node_pids().items():
            try:
                for task in Path(f"/proc/{pid}/task").iterdir():
                    kind = ("zenoh" if (task / "comm").read_text().startswith(ZENOH_THREADS)
                            else "main")
                    role[int(task.name)] = f"{node} {kind}"
            except OSError:
                continue
        _tracefs("tracing_on", "1")
        time.sleep(window_s)
        _tracefs("tracing_on", "0")
        run.wait()
        trace = (TRACEFS / "trace").read_text()
        _tracefs("events/enable", "0")
        steps_per_s = json.loads((Path(tmp) / "run" / "summary.json").read_text())["steps_per_s"]
    busy: dict[int, dict[str, float]] = {}
    last: dict[int, tuple[str, float]] = {}  # core -> (who runs, since)
    for m in _SWITCH.finditer(trace):
        core, t, nxt = int(m.group(1)), float(m.group(2)), int(m.group(4))
        if core in last:
            who, since = last[core]
            busy.setdefault(core, {})[who] = busy.get(core, {}).get(who, 0.0) + t - since
        last[core] = ("idle" if nxt == 0 else role.get(nxt, "other"), t)
    steps = window_s * steps_per_s
    return {f"core {c}": {w: round(1e6 * v / steps, 1) for w, v in sorted(
        per.items(), key=lambda kv: -kv[1]) if 1e6 * v / steps >= 0.5}
        for c, per in sorted(busy.items())}


def main(argv: list[str] | None = None) -> int:
    from bench.bench_zenoh_pingpong import one as pingpong
    from bench.workloads import WORKLOADS

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="one JSON object on the last line")
    ap.add_argument("--repeats", type=int, default=1, help="runs of each kind per workload")
    ap.add_argument("--rows", default="lumped,corner,corner_fatigue,full")
    ap.add_argument("--trace", action="store_true",
                    help="then one traced distributed run of each row: a step's timeline")
    ap.add_argument("--helics", action="store_true",
                    help="with the lumped row: the same car as 4 HELICS federates "
                         "(pip install helics), over its zmq, tcp_ss and ipc cores")
    ap.add_argument("--sched", action="store_true",
                    help="then one distributed run of each row with the kernel's scheduler "
                         "events (root): each core's time per step by node and thread")
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
    if args.helics and "lumped" in out:
        split = {core: helics_split(T_END["lumped"], core) for core in ("zmq", "tcp_ss", "ipc")}
        best = max(split, key=lambda c: split[c]["steps_per_s"])
        lumped = cast(dict[str, float], out["lumped"])["coupled_steps_s"]
        same = _last_row_of_hold_run(T_END["lumped"]) == split[best]["last"]
        out["helics"] = {**{c: round(r["steps_per_s"], 1) for c, r in split.items()},
                         "lumped_over_best": round(lumped / split[best]["steps_per_s"], 2),
                         "same_bits_as_hold_run": same}
        print("\nlumped quarter car as 4 HELICS federates, steps/s: " + ", ".join(
            f"{c} {r['steps_per_s']:.0f}" for c, r in split.items())
            + f"; suscosim's distributed run {lumped / split[best]['steps_per_s']:.1f}x the "
            f"best ({best}); its last row {'=' if same else '!='} suscosim's (coupling hold)",
            flush=True)
    for key, label, scenario, fatigue in WORKLOADS if args.sched else ():
        if key in rows:
            cores = sched_profile(scenario, fatigue, 10 * T_END[key])
            out[f"{key}_sched_us"] = cores
            print(f"\n{label}, each core's time per coupled step [us] (sched_switch):\n"
                  + "\n".join(f"  {c}: " + ", ".join(f"{w} {v:.0f}" for w, v in per.items())
                               for c, per in cores.items()), flush=True)
    out["zenoh_rtt_us"] = round(rtt, 1)
    out["load"] = [round(x, 2) for x in loads]
    if args.json:
        print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
