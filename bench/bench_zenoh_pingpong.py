"""Zenoh ping-pong between two processes: round-trip time and CPU per round trip.

What one lock-step exchange costs on this machine with the transport options suscosim can use
(callback vs FIFO-channel subscriber, low-latency transport, express publishers), so that the
per-step budget of a co-simulation can be reasoned about.

    python bench/bench_zenoh_pingpong.py [--n 3000]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time

PONG = r"""
import json, sys, zenoh
from cosim.bus import zenoh_config
opts = json.loads(sys.argv[1])
conf = zenoh_config(connect=[opts["ep"]], listen=["tcp/127.0.0.1:0"], lowlatency=opts["ll"])
s = zenoh.open(conf)
pub = s.declare_publisher("bench/pong", express=opts["express"],
                          congestion_control=zenoh.CongestionControl.BLOCK)
if opts["fifo"]:
    sub = s.declare_subscriber("bench/ping", zenoh.handlers.FifoChannel(64))
    print("ready", flush=True)
    while True:
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


def one(n: int, fifo: bool, ll: bool, express: bool) -> dict:
    import queue

    import zenoh

    from cosim.bus import free_loopback_endpoint, zenoh_config

    ep = free_loopback_endpoint()
    s = zenoh.open(zenoh_config(listen=[ep], lowlatency=ll))
    opts = json.dumps({"ep": ep, "ll": ll, "fifo": fifo, "express": express})
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    p = subprocess.Popen([sys.executable, "-c", PONG, opts], stdout=subprocess.PIPE, text=True,
                         env=dict(os.environ, PYTHONPATH=root))
    assert p.stdout.readline().strip() == "ready"
    pub = s.declare_publisher("bench/ping", express=express,
                              congestion_control=zenoh.CongestionControl.BLOCK)
    q: queue.SimpleQueue = queue.SimpleQueue()
    if fifo:
        sub = s.declare_subscriber("bench/pong", zenoh.handlers.FifoChannel(64))
        get = lambda: sub.recv().payload.to_bytes()  # noqa: E731
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
    return {"fifo": fifo, "lowlatency": ll, "express": express,
            "rtt_us": wall / n * 1e6, "ping_cpu_us": cpu / n * 1e6}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=3000)
    args = ap.parse_args()
    print("| subscriber | lowlatency | express | round trip (us) | "
          "CPU of one side per round trip (us) |")
    print("|---|---|---|---|---|")
    for fifo in (False, True):
        for ll in (False, True):
            for express in (True, False):
                r = one(args.n, fifo, ll, express)
                print(f"| {'FIFO channel' if fifo else 'callback'} | {ll} | {express} | "
                      f"{r['rtt_us']:.0f} | {r['ping_cpu_us']:.0f} |", flush=True)


if __name__ == "__main__":
    main()
