"""What to tap and where: key expressions from RUN and PATTERN, endpoints from a run
folder's ``run.json``."""

from __future__ import annotations

import re
import socket
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cosim import keys
from cosim.errors import ScenarioError
from cosim.run_folder import read_json
from cosim.zenoh_options import is_loopback

DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"
_CHUNK = re.compile(r"^(\*\*?|[A-Za-z0-9][A-Za-z0-9_.-]{0,63})$")


class TapInputError(ValueError):
    """Bad tap input (run, pattern, file, endpoint): exit code 2 with this message."""


def channel_keyexpr(pattern: str | None) -> str:
    """``plant/state``, ``*/force``, ``plant`` (a node), ``**`` -> the ``node/channel`` part."""
    pattern = (pattern or "**").strip().strip("/")
    chunks = pattern.split("/") if pattern else ["**"]
    for c in chunks:
        if not _CHUNK.match(c):
            raise TapInputError(f"pattern {pattern!r}: chunk {c!r} is not a name, '*' or '**'")
    if len(chunks) == 1 and chunks[0] != "**":
        chunks.append("*")  # a node: its every channel
    if len(chunks) > 2 and "**" not in chunks:
        raise TapInputError(f"pattern {pattern!r}: expected NODE/CHANNEL (two names at most)")
    return "/".join(chunks)


def tap_keyexpr(run: str | None, pattern: str | None) -> str:
    run = run or "*"
    if run != "*":  # a run id
        try:
            keys.check_name("run", run)
        except ScenarioError:
            raise TapInputError(f"run {run!r}: not a run id (letters, digits, '_', '.', '-'), "
                                "'*' or a run folder") from None
    return f"{keys.PREFIX}/{run}/{channel_keyexpr(pattern)}"


@dataclass
class Target:
    keyexpr: str
    endpoints: list[str]
    lowlatency: bool = False
    source: str = ""
    note: str = ""


def _local(ep: str) -> str:
    for anyaddr in ("0.0.0.0", "[::]"):
        ep = ep.replace(f"/{anyaddr}:", "/127.0.0.1:")
    return ep


def resolve_target(run: str | None, pattern: str | None, connect: list[str] | None) -> Target:
    endpoints: list[str] = list(connect or [])
    lowlatency, source, note = False, "", ""
    if run and Path(run).is_dir():
        folder = Path(run)
        if (folder / "summary.json").exists():
            note = f"{folder} has a summary.json: that run has ended (tapping anyway)"
        meta: dict[str, Any] = {n: doc for n in ("run.json", "scenario.json")
                                if (doc := read_json(folder / n)) is not None}
        if not meta:
            raise TapInputError(f"{folder}: not a run folder (no run.json or scenario.json)")
        rj = meta.get("run.json") or {}
        run = rj.get("run_id") or ((meta.get("scenario.json") or {}).get("run") or {}).get("id")
        if not run:
            raise TapInputError(f"{folder}: no run id in run.json or scenario.json")
        eps = rj.get("endpoints") or {}
        if not endpoints:  # through the run's router if it has one, else to the orchestrator
            endpoints = list(eps.get("connect", [])) or [_local(e) for e in eps.get("listen", [])]
            source = f"{folder / 'run.json'}" if endpoints else ""
            host = rj.get("host")
            if host and host != socket.gethostname() and endpoints and \
                    all(is_loopback(e) for e in endpoints):
                note = (f"the run is on host {host} and listens on loopback only: not "
                        "reachable from here (start it with --listen tcp/0.0.0.0:PORT)")
        lowlatency = bool(rj.get("lowlatency", False))
        if rj and not endpoints:
            raise TapInputError(f"{folder}: run.json records no endpoint (a "
                                f"{rj.get('mode') or 'non-distributed'} run has no bus to tap)")
    elif run and "/" in run:
        if pattern:
            raise TapInputError(f"{run}: not a run folder")
        run, pattern = "*", run
    if not endpoints:
        endpoints, source = [DEFAULT_ENDPOINT], "default"
    return Target(tap_keyexpr(run, pattern), endpoints, lowlatency, source, note)
