"""The explicit Zenoh mesh of a run's local nodes: who listens where and who connects to whom.

The orchestrator and the run's node processes on this machine link directly, a full mesh over
Unix sockets in a private folder (mode 0700), gossip off in every session: the orchestrator
listens on ``orchestrator.sock`` (besides its TCP endpoint); node *i* (scenario order) listens
on ``NAME.sock`` and connects to the orchestrator's and the earlier nodes' sockets, so each
pair is linked once, by one side. Why (no link-state forwarding, no wedged start): docs/cosim.md
"The explicit mesh" and "A wedged start". Sockets rather than ports chosen in advance: a path
in the run's own folder cannot be taken by another program meanwhile. Paths stay under the 107
bytes of a Unix socket path; the folder of an orchestrator killed outright is removed by the
next run (:func:`remove_stale`). Taps, scopes and replays join as clients of the orchestrator
(:func:`cosim.zenoh_options.session_mode`).
"""

from __future__ import annotations

import os
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

ORCHESTRATOR = "orchestrator"
PREFIX = "suscosim-mesh-"
"""The name of a mesh folder starts so, in the system's temporary folder."""
OWNER_FILE = "owner.pid"
"""The file in a mesh folder holding the process id of the orchestrator that made it."""
SOCKET_PATH_MAX = 107
"""The longest path a Unix socket may have on Linux (``sun_path`` is 108 bytes) [bytes]."""


def unix_endpoint(path: Path) -> str:
    """The Zenoh endpoint of a Unix stream socket at ``path``."""
    return f"unixsock-stream/{path}"


@dataclass
class LocalMesh:
    """The socket folder of one run's explicit mesh (:func:`create`), and each member's
    endpoints: ``names`` are the local nodes in the order they are started."""

    folder: Path
    names: list[str] = field(default_factory=list)

    @classmethod
    def create(cls, names: list[str]) -> LocalMesh:
        """A new private folder (mode 0700) for the sockets of ``names`` and the orchestrator,
        under the system's temporary folder, or under ``/tmp`` when a socket path there would
        be too long (a deep ``TMPDIR``). Raises ValueError for a name that is not a plain
        file name or when no folder gives short enough paths, OSError when none can be made."""
        error: ValueError | None = None
        for base in dict.fromkeys([tempfile.gettempdir(), "/tmp"]):
            remove_stale(Path(base))
            folder = Path(tempfile.mkdtemp(prefix=PREFIX, dir=base))
            (folder / OWNER_FILE).write_text(str(os.getpid()))
            mesh = cls(folder, list(names))
            try:
                for name in [ORCHESTRATOR, *mesh.names]:
                    mesh.socket(name)
                return mesh
            except ValueError as exc:
                mesh.remove()
                error = exc
        assert error is not None
        raise error

    def socket(self, name: str) -> Path:
        """The socket path of member ``name`` (a node or :data:`ORCHESTRATOR`)."""
        if not name or "/" in name or name in (".", ".."):
            raise ValueError(f"mesh member name {name!r} is not a plain file name")
        path = self.folder / f"{name}.sock"
        if len(str(path).encode()) > SOCKET_PATH_MAX:
            raise ValueError(f"socket path {path} is longer than {SOCKET_PATH_MAX} bytes "
                             f"(set TMPDIR to a shorter folder)")
        return path

    def listen(self, name: str) -> str:
        """The endpoint member ``name`` listens on."""
        return unix_endpoint(self.socket(name))

    def connect(self, name: str) -> list[str]:
        """The endpoints node ``name`` connects to: the orchestrator's, then those of the nodes
        started before it (each pair of the mesh is linked by exactly one side)."""
        before = self.names[:self.names.index(name)]
        return [self.listen(ORCHESTRATOR), *(self.listen(n) for n in before)]

    def remove(self) -> None:
        """Remove the socket folder (once every member has closed; idempotent)."""
        shutil.rmtree(self.folder, ignore_errors=True)


def remove_stale(base: Path | None = None) -> list[Path]:
    """Remove the mesh folders of this user in ``base`` (default: the temporary folder)
    whose orchestrator process is gone (killed before it could remove its own); return them.
    A folder without a readable owner file is left alone (it may be one being made now)."""
    removed = []
    for folder in (base or Path(tempfile.gettempdir())).glob(f"{PREFIX}*"):
        try:
            if folder.stat().st_uid != os.getuid():
                continue
            pid = int((folder / OWNER_FILE).read_text())
        except (OSError, ValueError):
            continue
        if not Path(f"/proc/{pid}").exists():
            shutil.rmtree(folder, ignore_errors=True)
            removed.append(folder)
    return removed
