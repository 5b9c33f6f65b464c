"""The node processes a run starts on this machine: command lines, logs, cores, fate."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

from cosim import auth as au
from cosim import node_kinds as nk
from cosim.bus import NODE_RUNTIME
from cosim.orchestrator_presence import ENV_PARENT_PID

from . import placement as pl
from .local_mesh import LocalMesh


def local_lease_ms(stall_timeout_s: float) -> int:
    """Zenoh link lease [ms] of the orchestrator and its nodes: the stall timeout clamped to
    2-30 s, so a starved process is judged by one rule (a shorter lease drops its messages)."""
    return int(1000.0 * min(max(stall_timeout_s, 2.0), 30.0))


class LocalNodes:
    def __init__(self, run_id: str, names: list[str], connect: list[str], lowlatency: bool,
                 log_dir: Path, zenoh_config_file: str | None = None,
                 cores: dict[str, int] | None = None, lease_ms: int = 2000,
                 run_key: bytes | None = None, mesh: LocalMesh | None = None) -> None:
        """Start ``names`` as ``suscosim node`` processes (output in ``log_dir/NAME.log``)."""
        self.mesh = mesh
        self.procs: dict[str, subprocess.Popen] = {}
        self.cores: dict[str, int] = {}  # the core each node was pinned to
        self.background: list[str] = []  # the nodes put in SCHED_IDLE (go_background)
        self.batch: list[str] = []  # the coupled nodes sharing a core: SCHED_BATCH
        self.zenoh_cores: dict[str, int] = {}  # coupled node -> its Zenoh threads' core
        shared = pl.sharing_a_core(cores or {})
        self.guard = pl.BackgroundGuard()
        log_dir.mkdir(parents=True, exist_ok=True)
        # their parent's PID: a node ends at once when this process is gone
        env = dict(os.environ, PYTHONUNBUFFERED="1", **{ENV_PARENT_PID: str(os.getpid())})
        env.setdefault("ZENOH_RUNTIME", NODE_RUNTIME)  # Zenoh's threads (cosim/bus.py)
        if run_key is not None:  # the run key, in the environment (readable by this user only)
            env[au.ENV_RUN_KEY] = run_key.hex()
        for name in names:
            cmd = [sys.executable, "-m", "orchestrator", "node", name, "--run", run_id,
                   "--mode", "peer"]  # the local mesh; nodes elsewhere are clients
            for ep in [*(mesh.connect(name) if mesh else []), *connect]:
                cmd += ["--connect", ep]
            if mesh is not None:
                cmd += ["--listen", mesh.listen(name), "--no-gossip"]
            if lowlatency:
                cmd.append("--lowlatency")
            if zenoh_config_file:
                cmd += ["--zenoh-config", zenoh_config_file]
            cmd += ["--lease-ms", str(int(lease_ms))]
            core = (cores or {}).get(name)
            if core is not None:
                cmd += ["--spin-us", str(pl.spin_us(name, cores or {}))]
            log = open(log_dir / f"{name}.log", "wb")
            self.procs[name] = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT,
                                                stdin=subprocess.DEVNULL, env=env)
            log.close()
            # before its interpreter has started any thread: they all inherit the core
            if core is not None and pl.pin(self.procs[name].pid, core):
                self.cores[name] = core
                if name in shared and pl.batch(self.procs[name].pid):
                    self.batch.append(name)

    def go_background(self) -> None:
        """Once started: pinned nodes off the critical path to ``SCHED_IDLE``; the Zenoh
        threads of coupled nodes to real time, of those sharing a core on another
        (:func:`.placement.zenoh_core`, :func:`.placement.move_zenoh_threads`)."""
        for name in self.cores:
            pid = self.procs[name].pid
            if self.procs[name].poll() is not None:
                continue
            if nk.off_critical_path(name):
                if pl.background(pid):
                    self.background.append(name)
            elif pl.move_zenoh_threads(pid, core := pl.zenoh_core(name, self.cores)):
                self.zenoh_cores[name] = core

    def check(self) -> str | None:
        """Every clock tick: a starved background node back to normal (said), then :meth:`dead`."""
        if self.background:
            alive = {n: self.procs[n].pid for n in self.background if self.procs[n].poll() is None}
            for name in self.guard.check(alive):
                print(f"suscosim: node '{name}' was starved of CPU in SCHED_IDLE (other "
                      f"programs keep its core busy): back in the normal class",
                      file=sys.stderr, flush=True)
        return self.dead()

    def dead(self) -> str | None:
        """A message naming a node process that exited with an error, if any."""
        for name, p in self.procs.items():
            code = p.poll()
            if code not in (None, 0):
                return f"node '{name}' exited with code {code} (see logs/{name}.log)"
        return None

    def stop(self, grace_s: float = 5.0, tick: Callable[[], None] | None = None,
             tick_period_s: float = 0.25) -> None:
        """Wait ``grace_s`` for the nodes to end, then SIGTERM, SIGKILL 2 s later."""
        deadline = time.monotonic() + grace_s
        for p in self.procs.values():
            while True:
                left = deadline - time.monotonic()
                try:
                    p.wait(timeout=max(0.05, min(left, tick_period_s if tick else left)))
                    break
                except subprocess.TimeoutExpired:
                    if time.monotonic() >= deadline:
                        p.terminate()
                        break
                    if tick is not None:
                        tick()
        for p in self.procs.values():
            try:
                p.wait(timeout=2)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        if self.mesh is not None:
            self.mesh.remove()
