"""Whether a run's orchestrator is still there, as one node sees it (without it nobody would
end the run). It is gone when its liveliness token dropped and stayed dropped for
:data:`ORCHESTRATOR_GONE_S`, or (a local node) when the process that started the node ended:
the orchestrator puts its PID in its children's environment (:data:`ENV_PARENT_PID`), and an
orphan's ``os.getppid()`` changes at once.
"""

from __future__ import annotations

import os
import time
from collections.abc import Mapping

ENV_PARENT_PID = "SUSCOSIM_PARENT_PID"
ORCHESTRATOR_GONE_S = 2.0
"""The orchestrator's liveliness token must stay dropped this long before a node gives up
(Zenoh can drop and re-declare a token while links reorganise under heavy CPU load) [s]."""


def parent_from_env(environ: Mapping[str, str] | None = None) -> int | None:
    """The orchestrator's PID if this process is a local node that it started, else None."""
    raw = (os.environ if environ is None else environ).get(ENV_PARENT_PID, "")
    try:
        pid = int(raw)
    except ValueError:
        return None
    return pid if pid > 1 else None


def parent_gone(pid: int | None) -> bool:
    """``pid`` (:func:`parent_from_env`) is no longer this process's parent."""
    return pid is not None and os.getppid() != pid


class OrchestratorPresence:
    """The orchestrator of run ``run`` as node ``node`` sees it: :meth:`on_token` watches its
    liveliness token (bus thread); ``parent``: :func:`parent_from_env`."""

    def __init__(self, run: str, node: str, parent: int | None) -> None:
        self.run, self.node, self.parent = run, node, parent
        self._seen = False
        self._gone: float | None = None  # when the token dropped [monotonic s]

    def on_token(self, _key: str, alive: bool) -> None:
        if alive:
            self._seen, self._gone = True, None
        elif self._seen and self._gone is None:
            self._gone = time.monotonic()

    def why_gone(self) -> str | None:
        """Why the orchestrator counts as gone (the node's error), or None."""
        if parent_gone(self.parent):
            return (f"{self.node}: the orchestrator of run '{self.run}' is gone (its process "
                    f"{self.parent}, which started this node, ended)")
        gone = self._gone
        if gone is not None and time.monotonic() - gone > ORCHESTRATOR_GONE_S:
            return (f"{self.node}: the orchestrator of run '{self.run}' is gone (its liveliness "
                    "token dropped)")
        return None
