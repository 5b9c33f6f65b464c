"""A user's node as a class: the lock-step shell around ``step``, for a kind of the registry.

``[nodes] controller = "mypackage.mymodule:MyController"`` names a class; the node process
(``suscosim node controller``) runs it with :func:`run_stepped`: it declares the kind's
outputs (:attr:`cosim.node_kinds.NodeKind.writes`), listens to its inputs
(:func:`cosim.node_kinds.inputs`), does the start handshake, then every step k::

    node = MyController(scenario, start)          # once, after the start handshake
    out = node.step(k, t, inputs)                 # every step k = 0..N, t = k h [s]
    node.close()                                  # at the end, if it has one

``start`` is the orchestrator's start payload (``n_steps``, ``h``, ``info``: every node's
facts, e.g. ``start["info"]["plant"]["n_corners"]``). ``inputs`` maps ``"node/channel"`` to
that input's fields as numpy arrays (``inputs["plant/state"]["v_b"]``), the plant's state of
step k (of step k - 1 in the parallel exchange). ``step`` returns the fields of its output:
``{"F_d": ..., "c_eff": ...}`` for a kind with one output channel, or ``{channel: fields}``.
The fields the plant couples through (:attr:`NodeKind.provides`: F_d and c_eff for the
controller, F_t and k_t for the tyre/road node) must be there, else the run ends with a
:class:`RunError` naming them. An optional ``preflight(scenario, facts)`` (a static or class
method) is run by the orchestrator before any process starts (see
:func:`cosim.node_kinds.run_preflight`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from . import node_kinds as nk
from .errors import RunError
from .participant import Participant

LAGGED = (("plant", "state"),)
"""Inputs a node takes from the previous step in the parallel exchange (the force nodes
compute step k's forces from the state of step k - 1)."""


def outputs_of(kind: nk.NodeKind, out: Any, k: int) -> dict[str, Mapping[str, Any]]:
    """``step``'s result as channel -> fields (see the module's docstring)."""
    channels = [c for c in kind.writes if c != "records"]
    if not isinstance(out, Mapping):
        raise RunError(f"{kind.name}: step {k} returned a {type(out).__name__}, expected a "
                       "mapping of field -> value")
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
    run_cfg = scenario["run"]
    h = float(run_cfg["h"])
    lag = 0 if run_cfg["exchange"] == "sequential" else 1
    for channel in kind.writes:
        if channel != "records":
            part.output(channel)
    tags = [part.listen(node, channel) for node, channel in nk.inputs(name)]
    start = part.handshake(timeout_s=run_cfg["start_timeout_s"])
    n = int(start["n_steps"])
    node = cls(scenario, start)
    try:
        for k in range(n + 1):
            t = k * h
            msgs = part.wait({tag: max(k - lag, 0) if tag in LAGGED else k for tag in tags})
            inputs = {f"{tag[0]}/{tag[1]}": {f: m.array(f) for f in m.d}
                      for tag, m in msgs.items()}
            for channel, fields in outputs_of(kind, node.step(k, t, inputs), k).items():
                part.publish(channel, k, t, fields)
            part.progress(k, t)
    finally:
        close = getattr(node, "close", None)
        if callable(close):
            close()
    part.finish(n, n * h)
