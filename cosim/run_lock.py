"""One run per run folder: a lock file that says which process holds the folder.

``RUN_DIR/.run.lock`` is locked with ``flock`` (exclusive, non-blocking) for the whole run
and holds the pid of the process that holds it. A second run given the same ``--out`` (or the
same run id, hence the same default folder) finds it locked and is refused with exit 2,
naming the pid, before it writes anything: two runs never write one journal. The lock is
the kernel's: it goes with the process, so a killed run leaves no stale lock (the file
stays, empty of meaning, and is taken over by the next run).
"""

from __future__ import annotations

import fcntl
import os
from pathlib import Path

from .errors import SuscosimError

LOCK_NAME = ".run.lock"


class FolderInUseError(SuscosimError):
    """The run folder is held by another live run (exit 2)."""

    exit_code = 2


class RunIdInUseError(SuscosimError):
    """The run id is live on the bus already (another run's orchestrator or nodes; exit 2)."""

    exit_code = 2


class RunLock:
    """The lock of one run folder; :meth:`release` (or process exit) frees it."""

    def __init__(self, folder: str | Path) -> None:
        self.path = Path(folder) / LOCK_NAME
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            try:
                holder = os.read(fd, 64).decode(errors="replace").strip() or "?"
            finally:
                os.close(fd)
            raise FolderInUseError(f"{folder}: the run folder is in use by another run "
                                   f"(pid {holder}); give another --out or wait for it "
                                   "to end") from None
        except OSError:
            os.close(fd)
            raise
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        self._fd: int | None = fd

    def release(self) -> None:
        """Free the folder (the file stays: removing it would race with a new run)."""
        if self._fd is not None:
            fd, self._fd = self._fd, None
            try:
                os.ftruncate(fd, 0)
            except OSError:
                pass
            os.close(fd)

    def __enter__(self) -> RunLock:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()
