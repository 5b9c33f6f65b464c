"""``--serve NODE``: the other machine's side of a sweep whose nodes are split across
machines through a Zenoh router."""

from __future__ import annotations

import subprocess
import sys
import time
from collections.abc import Iterable
from pathlib import Path
from typing import TextIO

from .phases import kill_group, point_state, start
from .spec import Sweep


def point_of_run(run_id: str, point_ids: Iterable[str]) -> str | None:
    """The point whose run this is (run ids: ``<point id>-<invocation token>``, or the id)."""
    from cosim import keys

    ids = set(point_ids)
    if run_id in ids:
        return run_id
    base, _, token = run_id.rpartition("-")
    if len(token) != 6 or any(c not in "0123456789abcdef" for c in token):
        return None  # not an invocation token (keys.invocation_token: 6 hex digits)
    for pid in ids:
        if base and run_id == keys.unique_run_id(pid, token):
            return pid
    return None


def serve(sweep: Sweep, nodes: list[str], connect: list[str], out: Path,
          stream: TextIO, poll_s: float = 1.0) -> int:
    """Start ``suscosim node NODE --run <id>`` for each point as soon as its orchestrator
    answers on the router, until every point is served (or done in a shared ``out``): 0, or
    130 when interrupted."""

    from cosim import keys
    from cosim.bus import ZenohBus, zenoh_config

    ids = {p.id: p for p in sweep.points}
    served_ok: set[str] = set()
    running: dict[str, list[subprocess.Popen]] = {}
    cooldown: dict[str, float] = {}  # a node that failed: wait before serving that id again
    logs = out / "serve"
    logs.mkdir(parents=True, exist_ok=True)
    bus = ZenohBus(zenoh_config(connect, None, mode="client"))  # through a router
    pattern = keys.key("*", keys.ORCHESTRATOR, keys.SCENARIO)
    stream.write(f"suscosim sweep {sweep.name}: serving {', '.join(nodes)} for "
                 f"{len(ids)} points via {', '.join(connect)}\n")
    stream.flush()
    try:
        while True:
            for pid in ids:
                if pid not in served_ok and point_state(ids[pid], sweep.run_dir(out, ids[pid]),
                                                        sweep.fatigue) == "done":
                    served_ok.add(pid)  # done in a shared sweep folder
            if len(served_ok) == len(ids) and not running:
                return 0
            live: dict[str, str] = {}  # point id -> the live run id of that point
            for reply in bus.session.get(pattern, timeout=min(0.5, poll_s)):
                if reply.ok is not None:
                    run_id = keys.parse_key(str(reply.ok.key_expr))[0]
                    point = point_of_run(run_id, ids)
                    if point is not None:
                        live[point] = run_id
            now = time.monotonic()
            for pid in sorted(live):
                if pid in served_ok or pid in running or cooldown.get(pid, 0.0) > now:
                    continue
                procs = []
                for n in nodes:
                    cmd = [sys.executable, "-m", "orchestrator", "node", n, "--run", live[pid]]
                    for ep in connect:
                        cmd += ["--connect", ep]
                    procs.append(start(cmd, logs / f"{pid}.{n}.log"))
                running[pid] = procs
                stream.write(f"  {pid}: started {', '.join(nodes)}\n")
                stream.flush()
            for pid, procs in list(running.items()):
                codes = [pr.poll() for pr in procs]
                if any(c is None for c in codes):
                    continue
                del running[pid]
                if all(c == 0 for c in codes):
                    served_ok.add(pid)
                    stream.write(f"  {pid}: done ({len(served_ok)}/{len(ids)})\n")
                else:
                    cooldown[pid] = time.monotonic() + 10.0
                    stream.write(f"  {pid}: node exit codes {codes} (served again if the "
                                 f"sweep reruns it)\n")
                stream.flush()
            time.sleep(poll_s)
    except KeyboardInterrupt:
        return 130
    finally:
        for procs in running.values():
            for pr in procs:
                kill_group(pr)
        bus.close()

