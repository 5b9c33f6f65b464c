"""``suscosim cluster [--workers N] [--threads T]``: a local Dask scheduler and N workers of T
threads (T points at once) to try ``suscosim sweep --executor dask`` (docs/sweeps.md), until
Ctrl-C/SIGTERM. Exit codes: 0 stopped, 1 the scheduler died, 2 bad arguments or no
``distributed``.
"""

from __future__ import annotations

import argparse
import signal
import socket
import subprocess
import sys
import time
from functools import partial

from .cli_util import fail, interrupt_on_sigterm, parse_args
from .sweep.phases import child_env

_fail = partial(fail, "suscosim cluster")


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="suscosim cluster",
                                 description="a local Dask scheduler and workers for "
                                             "'suscosim sweep --executor dask'")
    ap.add_argument("--workers", type=int, default=2, help="worker processes (default 2)")
    ap.add_argument("--threads", type=int, default=1,
                    help="threads per worker = points it runs at once (default 1)")
    ap.add_argument("--host", default="127.0.0.1",
                    help="address the scheduler and workers listen on (default loopback; "
                         "0.0.0.0 for workers on other machines)")
    ap.add_argument("--port", type=int, default=8786, help="scheduler port (default 8786)")
    ap.add_argument("--no-nanny", action="store_true",
                    help="workers without a nanny (a killed worker is not restarted)")
    ap.add_argument("--dashboard", action="store_true",
                    help="the scheduler's web dashboard on port 8787")
    ap.add_argument("--local-directory", help="workers' scratch folder (default: a "
                    "temporary folder); a point's run folder is built there")
    return ap


def _wait_port(host: str, port: int, proc: subprocess.Popen, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and proc.poll() is None:
        try:
            with socket.create_connection((host, port), timeout=0.5):
                return True
        except OSError:
            time.sleep(0.2)
    return False


def _stop(procs: list[subprocess.Popen]) -> None:
    for group in (procs[1:], procs[:1]):
        for p in group:
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
        deadline = time.monotonic() + 10.0
        for p in group:
            try:
                p.wait(timeout=max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


def main(argv: list[str] | None = None) -> int:
    args = parse_args(build_parser(), argv)
    if isinstance(args, int):
        return args
    for name in ("workers", "threads"):
        if getattr(args, name) < 1:
            return _fail(f"--{name} must be >= 1")
    if not 0 < args.port < 65536:
        return _fail("--port must be in 1-65535")
    try:
        import distributed  # noqa: F401
    except ImportError:
        return _fail("needs the 'distributed' package (python3 -m pip install "
                     "'dask[distributed]')")
    address = f"tcp://{args.host}:{args.port}"
    py = sys.executable
    sched_cmd = [py, "-m", "distributed.cli.dask_scheduler", "--host", args.host,
                 "--port", str(args.port)]
    sched_cmd += ["--dashboard-address", ":8787"] if args.dashboard else ["--no-dashboard"]
    procs: list[subprocess.Popen] = []

    old = interrupt_on_sigterm()
    try:
        # one point per worker thread at a time: with Dask's default saturation (1.1) a
        # 1-thread worker is sent 2 points and runs them in turn while another worker idles
        sched_env = dict(child_env(), DASK_DISTRIBUTED__SCHEDULER__WORKER_SATURATION="1.0")
        sched = subprocess.Popen(sched_cmd, env=sched_env, stdin=subprocess.DEVNULL)
        procs.append(sched)
        connect_host = "127.0.0.1" if args.host in ("0.0.0.0", "") else args.host
        if not _wait_port(connect_host, args.port, sched, 30.0):
            return _fail(f"the scheduler did not start on {address} (port in use?)", 1)
        for i in range(args.workers):
            cmd = [py, "-m", "distributed.cli.dask_worker", f"tcp://{connect_host}:"
                   f"{args.port}", "--nthreads", str(args.threads), "--name", f"w{i}",
                   "--host", args.host if args.host not in ("0.0.0.0", "") else "127.0.0.1",
                   "--no-dashboard", "--nanny" if not args.no_nanny else "--no-nanny"]
            if args.local_directory:
                cmd += ["--local-directory", args.local_directory]
            procs.append(subprocess.Popen(cmd, env=child_env(), stdin=subprocess.DEVNULL))
        print(f"suscosim cluster: scheduler {address}, {args.workers} workers x "
              f"{args.threads} threads (Ctrl-C stops them)\n"
              f"  suscosim sweep SWEEP.toml --executor dask --scheduler {address}", flush=True)
        while True:
            if sched.poll() is not None:
                print(f"suscosim cluster: the scheduler exited ({sched.returncode})",
                      file=sys.stderr)
                return 1
            time.sleep(0.5)
    except KeyboardInterrupt:
        return 0
    finally:
        signal.signal(signal.SIGTERM, old)
        _stop(procs)
