"""A distributed run's nodes: one process per node on Zenoh (the runner's clock runs on them)."""

from __future__ import annotations

from collections.abc import Callable
from contextlib import suppress
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cosim.bus import LOOPBACK_LISTEN, Bus, ZenohBus, zenoh_config
from cosim.errors import InputFileError, RunError
from cosim.run_lock import check_run_id_free

from .local_mesh import ORCHESTRATOR, LocalMesh
from .local_nodes import LocalNodes, local_lease_ms
from .placement import core_layout, should_pin, usable_cores


@dataclass
class Nodes:
    bus: Bus
    dead: Callable[[], str | None]  # why a node is gone, or None (every clock tick)
    local: LocalNodes | None = None

    def started(self) -> None:
        if self.local is not None:
            self.local.go_background()

    def stop(self, grace_s: float = 5.0, tick: Callable[[], None] | None = None) -> None:
        if self.local:
            self.local.stop(grace_s=grace_s, tick=tick)


def close_quietly(bus: Bus) -> None:
    """Close ``bus`` on an error path (the first error is the one to report)."""
    with suppress(Exception):
        bus.close()


def distributed(run: dict[str, Any], folder: Path, connect: list[str] | None,
                external: list[str] | None, listen: list[str], lowlatency: bool,
                zenoh_config_file: str | None, pin_mode: str, run_key: bytes,
                as_client: bool) -> Nodes:
    """The orchestrator's Zenoh session and a process per node not ``external``: linked as an
    explicit mesh (:mod:`.local_mesh`) unless a Zenoh configuration file decides (gossip);
    the orchestrator gossips only through a ``connect``ed router (where a second run of the
    same id is refused). Its own session is universal; ``lowlatency`` is the nodes'."""

    lease = local_lease_ms(float(run["stall_timeout_s"]))
    names = [n for n in run["nodes"] if n not in (external or [])]
    try:
        mesh = LocalMesh.create(names) if names and not zenoh_config_file else None
    except (OSError, ValueError) as exc:
        raise RunError(f"cannot make the folder of the run's node sockets: {exc}") from None
    own_listen = list(listen or []) or None
    if mesh is not None:
        own_listen = [*(listen or [LOOPBACK_LISTEN]), mesh.listen(ORCHESTRATOR)]
    bus: ZenohBus | None = None
    try:
        bus = ZenohBus(zenoh_config(connect or [], own_listen, lowlatency=False,
                                    lease_ms=lease, config_file=zenoh_config_file,
                                    default_mode="client" if as_client else "peer",
                                    gossip=mesh is None or bool(connect)))
        if connect:  # the embedded mesh is this run's own: only a shared one can collide
            check_run_id_free(bus, run["id"], list(external or []))
        cores = usable_cores()
        layout = core_layout(run["nodes"], cores) if should_pin(pin_mode, cores) else {}
        # with the mesh, the nodes reach the orchestrator on its socket (and a router given
        # by --connect); without, through its endpoints, and each other by gossip
        reach = list(connect or []) if mesh is not None else list(connect or listen or [])
        try:
            local = LocalNodes(run["id"], names, reach, lowlatency, folder / "logs",
                               zenoh_config_file, layout, lease_ms=lease, run_key=run_key,
                               mesh=mesh)
        except OSError as exc:  # a node log that cannot be opened: nothing has started yet
            raise InputFileError(str(exc.filename or folder / "logs"),
                                 f"cannot write the node logs: {exc.strerror or exc}") from None
    except BaseException:  # nothing of the run is left behind
        if bus is not None:
            close_quietly(bus)
        if mesh is not None:
            mesh.remove()
        raise
    return Nodes(bus, local.check, local=local)
