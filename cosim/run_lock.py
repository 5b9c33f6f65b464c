"""One run per run folder, and one live run per run id on a shared bus. ``RUN_DIR/.run.lock``
is ``flock``ed for the whole run and holds its pid: a second run on the folder is refused
(exit 2, naming the pid) before it writes anything; the lock goes with the process."""

from __future__ import annotations

import fcntl
import os
import time
from pathlib import Path
from typing import TYPE_CHECKING

from . import keys
from .errors import SuscosimError

if TYPE_CHECKING:
    from .bus import Bus

LOCK_NAME = ".run.lock"


class FolderInUseError(SuscosimError):
    exit_code = 2


class RunIdInUseError(SuscosimError):  # live on the bus already
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


SETTLE_S = 1.0
"""How long :func:`live_nodes` looks for a run's liveliness tokens on a session just opened
[s]: a first query through a router can answer ``[]`` (up to ~0.3 s under load)."""
POLL_S = 0.05  # between two liveliness queries [s]


def live_nodes(bus: Bus, run_id: str, settle_s: float = SETTLE_S, poll_s: float = POLL_S,
               stop_at: set[str] | None = None) -> set[str]:
    """The nodes (``orchestrator`` included) of run ``run_id`` whose liveliness token is on
    the bus, looked for over ``settle_s`` [s]; early once a node outside ``stop_at`` is."""
    found: set[str] = set()
    pattern = keys.key(run_id, "*", keys.ALIVE)

    def note(key: str) -> None:
        try:
            found.add(keys.parse_key(key)[1])
        except ValueError:
            pass

    def on_token(key: str, alive: bool) -> None:
        if alive:
            note(key)

    watcher = bus.watch(pattern, on_token)
    try:
        end = time.monotonic() + settle_s
        while True:
            for key in bus.alive(pattern, timeout=max(poll_s, 0.01)):
                note(key)
            if found - (stop_at if stop_at is not None else set()):
                break
            left = end - time.monotonic()
            if left <= 0:
                break
            time.sleep(min(poll_s, left))
    finally:
        undeclare = getattr(watcher, "undeclare", None)
        if callable(undeclare):
            try:
                undeclare()
            except Exception:  # a session closing under it: the watcher is gone anyway
                pass
    return set(found)


def check_run_id_free(bus: Bus, run_id: str, external: list[str],
                      settle_s: float = SETTLE_S) -> None:
    """Refuse (exit 2) a run id live on the bus already (``--external`` nodes are expected)."""
    taken = sorted(live_nodes(bus, run_id, settle_s, stop_at=set(external)) - set(external))
    if taken:
        raise RunIdInUseError(f"run id '{run_id}' is already live on the bus (live there "
                              f"now: {', '.join(taken)}): choose another run.id, or wait "
                              "for that run to end")
