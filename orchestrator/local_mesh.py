"""The explicit Zenoh mesh of a run's local nodes (docs/cosim.md "The explicit mesh"): a full
mesh over Unix sockets in a private folder (0700), gossip off: the orchestrator listens on
``orchestrator.sock``, node *i* on ``NAME.sock`` and connects to the orchestrator's and the
earlier nodes' sockets (each pair linked once). Sockets, not ports: a path in the run's own
folder cannot be taken meanwhile. A killed orchestrator's folder is removed by the next run.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

ORCHESTRATOR = "orchestrator"
PREFIX = "suscosim-mesh-"  # of a mesh folder, in the temporary folder
OWNER_FILE = "owner.pid"  # the pid of the orchestrator that made it
SOCKET_PATH_MAX = 107  # [bytes] Linux ``sun_path`` is 108


@dataclass
class LocalMesh:
    """One run's socket folder; ``names``: the local nodes in start order."""

    folder: Path
    names: list[str] = field(default_factory=list)

    @classmethod
    def create(cls, names: list[str]) -> LocalMesh:
        """A new private folder in the temporary folder (or ``/tmp``: shorter socket paths)."""
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
        if not name or "/" in name or name in (".", ".."):
            raise ValueError(f"mesh member name {name!r} is not a plain file name")
        path = self.folder / f"{name}.sock"
        if len(str(path).encode()) > SOCKET_PATH_MAX:
            raise ValueError(f"socket path {path} is longer than {SOCKET_PATH_MAX} bytes "
                             f"(set TMPDIR to a shorter folder)")
        return path

    def listen(self, name: str) -> str:
        return f"unixsock-stream/{self.socket(name)}"

    def connect(self, name: str) -> list[str]:
        """The orchestrator's and the earlier nodes' endpoints."""
        before = self.names[:self.names.index(name)]
        return [self.listen(ORCHESTRATOR), *(self.listen(n) for n in before)]

    def remove(self) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)


def remove_stale(base: Path | None = None) -> list[Path]:
    """Remove (and return) this user's mesh folders in ``base`` whose orchestrator is gone."""
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
