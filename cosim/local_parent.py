"""A node started by a local orchestrator ends as soon as that orchestrator's process is gone.

The orchestrator of ``suscosim run`` starts its local nodes as child processes and puts its
PID in their environment (:data:`ENV_PARENT_PID`). A node that finds its parent changed
(``os.getppid()``: a child whose parent died is adopted by init or a subreaper) knows the
orchestrator is dead, whatever the bus says. Without it a node whose orchestrator was killed
outright (SIGKILL, the OOM killer) before the node had fetched its scenario waited the fetch's
30 s for an answer (the orchestrator's liveliness token had never been seen, so its drop
said nothing); later in a run the token's drop ends the nodes after
``_ORCHESTRATOR_GONE_S`` (2 s). Nodes started elsewhere (another machine, a container) have
no such parent and rely on the bus alone.
"""

from __future__ import annotations

import os
from collections.abc import Mapping

ENV_PARENT_PID = "SUSCOSIM_PARENT_PID"
"""The PID of the orchestrator that started this node as its child (decimal)."""


def parent_from_env(environ: Mapping[str, str] | None = None) -> int | None:
    """The orchestrator's PID if this process is a local node that it started, else None
    (unset or not a PID). Not checked against ``os.getppid()`` here: an orchestrator killed
    before its last node's interpreter got this far is already gone, and
    :func:`parent_gone` says so at once."""
    raw = (os.environ if environ is None else environ).get(ENV_PARENT_PID, "")
    try:
        pid = int(raw)
    except ValueError:
        return None
    return pid if pid > 1 else None


def parent_gone(pid: int | None) -> bool:
    """True when ``pid`` (from :func:`parent_from_env`) is no longer this process's parent."""
    return pid is not None and os.getppid() != pid
