"""A user's node as a class: the lock-step shell around ``step``, for a kind of the registry.

``[nodes] controller = "mypackage.mymodule:MyController"`` names a class; the node process
runs it with :func:`run_stepped`: it declares the kind's outputs, listens to its inputs, does
the start handshake, then every step k::

    node = MyController(scenario, start)          # once, after the start handshake
    out = node.step(k, t, inputs)                 # every step k = 0..N, t = k h [s]
    node.close()                                  # at the end, if it has one

A class may have a ``FIELDS`` mapping of ``"node/channel"`` to the fields it needs of that
input (default: its required fields); a message without them is rejected.

``start`` is the orchestrator's start payload (``n_steps``, ``h``, ``info``: every node's
facts, e.g. ``start["info"]["plant"]["n_corners"]``). ``inputs`` maps ``"node/channel"`` to
that input's fields as numpy arrays (``inputs["plant/state"]["v_b"]``), the plant's state of
step k (of step k - 1 in the parallel exchange). ``step`` returns the fields of its output:
``{"F_d": ..., "c_eff": ...}`` for a kind with one output channel, or ``{channel: fields}``;
the fields the plant couples through (:attr:`NodeKind.provides`) must be there, else a
:class:`RunError` names them. An optional ``preflight(scenario, facts)`` (a static or class
method) runs before any process starts (:func:`cosim.node_kinds.run_preflight`).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from typing import Any

import numpy as np

from . import node_kinds as nk
from . import schema
from .checkpoint import CheckpointError
from .errors import RunError
from .participant import Participant
from .run_checkpoint import NodeCheckpoints
from .run_settings import LAGGED, RunSettings
from .wire import Message

__all__ = ["LAGGED", "Fields", "outputs_of", "run_stepped"]

_STATE = ("plant", "state")


class Fields(Mapping[str, np.ndarray]):
    """The fields of one input message as float arrays, each converted when first read."""

    __slots__ = ("_msg", "_cache")

    def __init__(self, msg: Message) -> None:
        self._msg = msg
        self._cache: dict[str, np.ndarray] = {}

    def __getitem__(self, name: str) -> np.ndarray:
        a = self._cache.get(name)
        if a is None:
            if name not in self._msg.d:
                raise KeyError(name)
            a = self._cache[name] = self._msg.array(name)
        return a

    def __contains__(self, name: object) -> bool:
        return name in self._msg.d

    def __iter__(self) -> Iterator[str]:
        return iter(self._msg.d)

    def __len__(self) -> int:
        return len(self._msg.d)


def _channels(kind: nk.NodeKind) -> list[str]:
    return [c for c in kind.writes if c not in ("step", "records")]


def outputs_of(kind: nk.NodeKind, out: Any, k: int) -> dict[str, Mapping[str, Any]]:
    """``step``'s result as channel -> fields, checked (see the module's docstring)."""
    if not isinstance(out, Mapping):
        raise RunError(f"{kind.name}: step {k} returned a {type(out).__name__}, expected a "
                       "mapping of field -> value")
    channels = _channels(kind)
    if out and all(c in channels and isinstance(v, Mapping) for c, v in out.items()):
        by_channel = dict(out)
    elif len(channels) == 1:
        by_channel = {channels[0]: out}
    else:
        raise RunError(f"{kind.name}: step {k} must return {{channel: fields}} for the "
                       f"channels {', '.join(channels)}")
    fields = by_channel.get("force")
    if kind.provides and fields is not None:
        missing = [f for f in kind.provides if f not in fields]
        if missing:
            raise RunError(f"{kind.name}: step {k}'s force lacks {', '.join(missing)} "
                           "(the plant couples through them)")
    return by_channel


def run_stepped(cls: Any, part: Participant, scenario: dict[str, Any], name: str) -> None:
    """Run the stepped node class ``cls`` as node ``name`` (a kind of the registry)."""
    kind = nk.kind(name)
    settings = RunSettings.of(scenario)
    wanted = getattr(cls, "FIELDS", None) or {}
    for channel in _channels(kind):
        part.output(channel)
    tags = [part.listen(node, channel,
                        required=wanted.get(f"{node}/{channel}", schema.required(node, channel)))
            for node, channel in nk.inputs(name)]
    names = {tag: f"{tag[0]}/{tag[1]}" for tag in tags}
    plan = NodeCheckpoints.of(scenario, name)
    part.start_at(plan.start_k)
    start = part.handshake(timeout_s=settings.start_timeout_s)
    n = int(start["n_steps"])
    h = settings.h
    node = cls(scenario, start)
    try:
        _check_can_checkpoint(node, plan, name)
        state = plan.restored()
        if state is not None:
            with plan.restoring():
                node.restore_state(state)
        # run.h = "auto": the plant chooses each step; its state's t says when a step is
        adaptive = settings.adaptive is not None  # and the last one is the one at t_end
        if adaptive and _STATE not in tags:
            raise RunError(f"{name}: run.h = 'auto' needs a node that reads plant/state")
        k = plan.start_k
        while True:
            msgs = part.wait(settings.needs(tags, k))
            t = msgs[_STATE].t if adaptive else k * h
            inputs = {names[tag]: Fields(m) for tag, m in msgs.items()}
            for channel, fields in outputs_of(kind, node.step(k, t, inputs), k).items():
                part.publish(channel, k, t, fields)
            part.send()  # the step's outputs in one message
            part.progress(k, t)
            if k + 1 in plan.due:  # the state at the start of step k + 1
                part.flush_records()
                plan.save(part, k + 1, node.checkpoint_state())
            if settings.is_last(k, t) or k >= n:
                break
            k += 1
    finally:
        close = getattr(node, "close", None)
        if callable(close):
            close()
    part.finish(k, t)


def _check_can_checkpoint(node: Any, plan: NodeCheckpoints, name: str) -> None:
    """CheckpointError before the first step if the run checkpoints and the node cannot."""
    if not plan.due and not plan.resuming:
        return
    if not callable(getattr(node, "checkpoint_state", None)) \
            or not callable(getattr(node, "restore_state", None)):
        raise CheckpointError(f"{name}: the node class {type(node).__name__} has no "
                              "checkpoint_state/restore_state (set run.checkpoint_every_s = 0)")
    refusal = getattr(node, "checkpoint_refusal", None)
    why = refusal() if callable(refusal) else None
    if why:
        raise CheckpointError(f"{name}: {why}")
