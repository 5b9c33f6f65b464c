"""Zenoh ping-pong between two processes: round-trip time and CPU per round trip.

What one lock-step exchange costs on this machine with the transport options suscosim can use
(callback vs FIFO-channel subscriber, low-latency transport, express publishers), so that the
per-step budget of a co-simulation can be reasoned about. ``--pinned`` adds the rows of the
run's own node configuration: both sides pinned to a core each and polling their FIFO for
``--spin-us`` before they block (the orchestrator's placement, orchestrator/placement.py).

    python bench/bench_zenoh_pingpong.py [--n 3000] [--pinned]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from typing import Any

PONG = r"""
import json, sys, zenoh
from cosim.bus import zenoh_config
opts = json.loads(sys.argv[1])
conf = zenoh_config(connect=[opts["ep"]], listen=["tcp/127.0.0.1:0"], lowlatency=opts["ll"])
s = zenoh.open(conf)
pub = s.declare_publisher("bench/pong", express=opts["express"],
                          congestion_control=zenoh.CongestionControl.BLOCK)
if opts["fifo"]:
    import os, time
    sub = s.declare_subscriber("bench/ping", zenoh.handlers.FifoChannel(64))
    spin = opts.get("spin_us", 0.0) * 1e-6
    print("ready", flush=True)
    while True:
        end = time.perf_counter() + spin
        while (smp := sub.try_recv()) is None and time.perf_counter() < end:
            os.sched_yield()
        if smp is None:
            smp = sub.recv()
        b = smp.payload.to_bytes()
        pub.put(b)
        if b == b"stop":
            break
else:
    import queue
    q = queue.SimpleQueue()
    sub = s.declare_subscriber("bench/ping", lambda smp: q.put(smp.payload.to_bytes()))
    print("ready", flush=True)
    while True:
        b = q.get()
        pub.put(b)
        if b == b"stop":
            break
s.close()
"""


def one(n: int, fifo: bool, ll: bool, express: bool, pinned: bool = False,
        spin_us: float = 200.0) -> dict:
    """One ping-pong of ``n`` round trips. ``pinned``: both sides in processes of their own,
    pinned to the first two usable cores, polling for ``spin_us`` before blocking (FIFO
    subscriber only)."""
    if pinned:
        return _pinned(n, ll, express, spin_us)
    return _one(n, fifo, ll, express)


def _pinned(n: int, ll: bool, express: bool, spin_us: float) -> dict:
    """:func:`one` with ``pinned``: the ping side is a child process pinned to the first core,
    its pong to the second."""
    from orchestrator.placement import pin, usable_cores

    cores = usable_cores()
    if len(cores) < 2:
        raise RuntimeError("pinned ping-pong needs 2 usable cores")
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    args = json.dumps({"n": n, "ll": ll, "express": express, "spin_us": spin_us,
                       "core": cores[1]})
    p = subprocess.Popen([sys.executable, os.path.abspath(__file__), "--child", args],
                         stdout=subprocess.PIPE, text=True, env=dict(os.environ, PYTHONPATH=root))
    pin(p.pid, cores[0])
    out, _ = p.communicate(timeout=120)
    return json.loads(out.strip().splitlines()[-1])


def _one(n: int, fifo: bool, ll: bool, express: bool, spin_us: float = 0.0,
         pong_core: int | None = None) -> dict:
    import queue

    import zenoh

    from cosim.bus import free_loopback_endpoint, zenoh_config

    ep = free_loopback_endpoint()
    s = zenoh.open(zenoh_config(listen=[ep], lowlatency=ll))
    opts = json.dumps({"ep": ep, "ll": ll, "fifo": fifo, "express": express,
                       "spin_us": spin_us})
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    p = subprocess.Popen([sys.executable, "-c", PONG, opts], stdout=subprocess.PIPE, text=True,
                         env=dict(os.environ, PYTHONPATH=root))
    if pong_core is not None:
        from orchestrator.placement import pin

        pin(p.pid, pong_core)
    assert p.stdout is not None and p.stdout.readline().strip() == "ready"
    pub = s.declare_publisher("bench/ping", express=express,
                              congestion_control=zenoh.CongestionControl.BLOCK)
    q: queue.SimpleQueue = queue.SimpleQueue()
    sub: Any
    if fifo:
        sub = s.declare_subscriber("bench/pong", zenoh.handlers.FifoChannel(64))
        spin = spin_us * 1e-6

        def get() -> bytes:
            end = time.perf_counter() + spin
            while (smp := sub.try_recv()) is None and time.perf_counter() < end:
                os.sched_yield()
            return (smp if smp is not None else sub.recv()).payload.to_bytes()
    else:
        sub = s.declare_subscriber("bench/pong", lambda smp: q.put(smp.payload.to_bytes()))
        get = q.get
    time.sleep(1.0)
    for _ in range(200):  # warm up, and make sure the path is there
        pub.put(b"x" * 100)
        get()
    r0 = resource.getrusage(resource.RUSAGE_SELF)
    t0 = time.perf_counter()
    for _ in range(n):
        pub.put(b"x" * 100)
        get()
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_SELF)
    pub.put(b"stop")
    p.wait(timeout=10)
    s.close()
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return {"fifo": fifo, "lowlatency": ll, "express": express, "pinned": pong_core is not None,
            "rtt_us": wall / n * 1e6, "ping_cpu_us": cpu / n * 1e6}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=3000)
    ap.add_argument("--pinned", action="store_true",
                    help="also the nodes' configuration: pinned, polling FIFO subscribers")
    ap.add_argument("--spin-us", type=float, default=200.0,
                    help="polling before blocking in the pinned rows [us]")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:  # the ping side of a pinned ping-pong (pinned by its parent)
        o = json.loads(args.child)
        print(json.dumps(_one(o["n"], True, o["ll"], o["express"], o["spin_us"], o["core"])))
        return
    print("| subscriber | lowlatency | express | pinned, polling | round trip (us) | "
          "CPU of one side per round trip (us) |")
    print("|---|---|---|---|---|---|")
    for fifo in (False, True):
        for ll in (False, True):
            for express in (True, False):
                r = one(args.n, fifo, ll, express)
                print(f"| {'FIFO channel' if fifo else 'callback'} | {ll} | {express} | no | "
                      f"{r['rtt_us']:.0f} | {r['ping_cpu_us']:.0f} |", flush=True)
    if args.pinned:
        for ll in (False, True):
            r = one(args.n, True, ll, True, pinned=True, spin_us=args.spin_us)
            print(f"| FIFO channel | {ll} | True | {args.spin_us:.0f} us | "
                  f"{r['rtt_us']:.0f} | {r['ping_cpu_us']:.0f} |", flush=True)


if __name__ == "__main__":
    main()
