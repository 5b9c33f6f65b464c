"""What a node's shell does about checkpoints in one run: when to save, where it starts, and
the state it starts from. The storage is :mod:`cosim.checkpoint`.

A checkpoint ``k`` is the run's state at the **start of step k** (t = k h [s]); a resumed (or
forked) run starts with step k. At each boundary a node sends what it still holds for the
steps < k, writes its whole state to ``RUN_DIR/checkpoints/k<k>/<node>.ckpt`` (a remote node:
the run folder mounted at the same path) and tells the clock (``checkpoint``: file, SHA-256,
size) without waiting; the clock writes the manifest once every node has. The recorder saves
once every step < k is in its journal, fsynced (its state is the journal, replayed on
resume); the fatigue node once it has taken load step k - 1.

``run.resume`` (set by ``suscosim run --resume`` / ``--fork``): ``{"k", "t", "folder",
"journal", "fresh": nodes that start afresh, "sha256": {node: its file's SHA-256 as the
orchestrator checked it}}``: a node reads its file only if it is still the one checked.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from .checkpoint import (
    RESUME_KEY,
    CheckpointError,
    checkpoint_key,
    checkpoint_steps,
    read_checkpoint,
    read_node_state,
    write_node_state,
)
from .errors import ScenarioError


class _Ctl(Protocol):
    def ctl(self, kind: str, k: int = -1, t: float = 0.0, **d: Any) -> None: ...


@dataclass(frozen=True)
class NodeCheckpoints:
    """One node's checkpoint plan in a run (from the resolved scenario)."""

    node: str
    run_dir: Path
    h: float  # communication step [s]
    due: frozenset[int]  # the boundaries k at which this run saves (none: off)
    start_k: int = 0  # 0, or the checkpoint's k of a resume or fork
    resume_folder: Path | None = None
    journal: Path | None = None  # the journal holding the steps < start_k (the recorder's)
    fresh: bool = False  # this node starts afresh at start_k (a fork changed its settings)
    sha256: str | None = None  # its file's SHA-256 as the orchestrator checked it

    @classmethod
    def of(cls, scenario: dict[str, Any], node: str) -> NodeCheckpoints:
        """The plan of ``node`` in the resolved ``scenario`` (ScenarioError for a bad period)."""
        run = scenario["run"]
        h = float(run["h"])
        every = float(run.get("checkpoint_every_s", 0.0) or 0.0)
        n = int(run["n_steps"])
        due: frozenset[int] = frozenset()
        if every > 0:
            try:
                due = frozenset(checkpoint_steps(every, h, n))
            except ValueError as exc:
                raise ScenarioError("run.checkpoint_every_s", every, str(exc)) from None
        res = run.get(RESUME_KEY) or {}
        if not res:
            return cls(node, Path(run["dir"]), h, due)
        k = int(res["k"])
        if not 0 < k <= n:
            raise ScenarioError("run.resume.k", k, f"a step of the run (1..{n})")
        sha = (res.get("sha256") or {}).get(node)
        return cls(node, Path(run["dir"]), h, frozenset(j for j in due if j > k), k,
                   Path(res["folder"]), Path(res["journal"]) if res.get("journal") else None,
                   node in res.get("fresh", ()), sha if isinstance(sha, str) else None)

    @property
    def resuming(self) -> bool:
        return self.resume_folder is not None

    def restored(self) -> dict[str, Any] | None:
        """This node's state at :attr:`start_k` (hash checked), or None: a fresh start."""
        if self.resume_folder is None or self.fresh:
            return None
        ckpt = read_checkpoint(self.resume_folder)
        if ckpt.k != self.start_k:
            raise CheckpointError(f"{self.resume_folder}: checkpoint k={ckpt.k}, the run "
                                  f"resumes at {self.start_k}")
        return read_node_state(ckpt, self.node, sha256=self.sha256)

    @contextmanager
    def restoring(self) -> Iterator[None]:
        """Around restoring the node: a state that does not fit it is a CheckpointError."""
        try:
            yield
        except CheckpointError:
            raise
        except (ValueError, KeyError, TypeError, AttributeError, IndexError) as exc:
            raise CheckpointError(f"{self.node}: its state in the checkpoint "
                                  f"{self.resume_folder} does not fit it: "
                                  f"{type(exc).__name__}: {exc}") from None

    def save(self, part: _Ctl, k: int, state: dict[str, Any]) -> None:
        """Write this node's ``state`` at ``k`` (signed with ``part``'s key), tell the clock."""
        auth = getattr(part, "auth", None)
        try:
            entry = write_node_state(self.run_dir, k, self.node, state,
                                     checkpoint_key(getattr(auth, "key", None)))
        except OSError as exc:
            raise CheckpointError(f"{self.node}: cannot write its checkpoint k={k} in "
                                  f"{self.run_dir}: {exc.strerror or exc}") from None
        part.ctl("checkpoint", k, k * self.h, **entry)
