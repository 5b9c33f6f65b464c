"""Control messages, field by field: what each kind must carry before anyone acts on it.

A malformed field of a control kind is a :class:`WireError` (rejected and counted), never a
crash. :func:`check_start` also checks that a ``start`` is the run the node fetched (same
number of steps and step size), with a table of facts for every node.

==========  ======================================================================  ========
kind        fields (payload ``d``)                                                  from
==========  ======================================================================  ========
ready       ``info``: map (``outputs``: list of str, the rest the node's facts)     node
waiting     ``missing``: list of str (inputs not heard yet)                         node
progress    ``rejected``: int >= 0 (messages this node rejected so far)             node
done        ``rejected``: int >= 0; recorder: ``rows`` int >= 0, ``files`` map      node
            str -> str, ``stats`` map, ``torn`` bool, ``undecodable`` int >= 0;
            fatigue: ``files`` str (its folder)
checkpoint  ``file``: str (``<node>.ckpt``), ``sha256``: 64 hex digits, ``bytes``:    node
            int >= 0: the node wrote its state at boundary k (cosim.run_checkpoint)
error       ``message``: str; ``exit_code``: 1 or 2; ``late``: list of str (the    node
            nodes whose input did not come, when that is the error)
start       ``n_steps``: int >= 1, ``h``: number > 0 [s], ``info``: map node -> map  clock
abort       ``reason``: str                                                         clock
done        (nothing)                                                               clock
==========  ======================================================================  ========
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

from .errors import WireError


def _int(d: Mapping[str, Any], name: str, kind: str, required: bool = False,
         low: int = 0) -> None:
    if name not in d:
        if required:
            raise WireError(f"{kind}: no field '{name}'")
        return
    v = d[name]
    if type(v) is not int or v < low:
        raise WireError(f"{kind}: field '{name}'={v!r:.40} is not an integer >= {low}")


def _str_list(d: Mapping[str, Any], name: str, kind: str) -> None:
    v = d.get(name, [])
    if type(v) is not list or not all(type(x) is str for x in v):
        raise WireError(f"{kind}: field '{name}'={v!r:.40} is not a list of strings")


def _map(d: Mapping[str, Any], name: str, kind: str, required: bool = False) -> None:
    if name not in d:
        if required:
            raise WireError(f"{kind}: no field '{name}'")
        return
    if type(d[name]) is not dict:
        raise WireError(f"{kind}: field '{name}'={d[name]!r:.40} is not a map")


def check_node_control(kind: str, d: Mapping[str, Any]) -> None:
    """WireError unless a node's control message has the fields of the table above."""
    if kind == "ready":
        _map(d, "info", kind)
        _str_list(d.get("info", {}), "outputs", kind)
    elif kind == "waiting":
        _str_list(d, "missing", kind)
    elif kind == "progress":
        _int(d, "rejected", kind)
    elif kind == "done":
        _int(d, "rejected", kind)
        _int(d, "rows", kind)
        _int(d, "undecodable", kind)
        _map(d, "stats", kind)
        files = d.get("files", {})
        if type(files) is not str:  # the fatigue node names its folder
            _map(d, "files", kind)
            if not all(type(k) is str and type(v) is str for k, v in files.items()):
                raise WireError(f"{kind}: field 'files' is not a map of strings")
        if "torn" in d and type(d["torn"]) is not bool:
            raise WireError(f"{kind}: field 'torn'={d['torn']!r:.40} is not a boolean")
    elif kind == "checkpoint":
        if type(d.get("file")) is not str or not d["file"].endswith(".ckpt"):
            raise WireError(f"{kind}: field 'file'={d.get('file')!r:.40} is not a .ckpt name")
        sha = d.get("sha256")
        if type(sha) is not str or len(sha) != 64 or any(c not in "0123456789abcdef"
                                                          for c in sha):
            raise WireError(f"{kind}: field 'sha256'={sha!r:.40} is not 64 hex digits")
        _int(d, "bytes", kind, required=True)
    elif kind == "error":
        if type(d.get("message")) is not str:
            raise WireError(f"{kind}: field 'message' is not a string")
        if d.get("exit_code", 1) not in (1, 2) or type(d.get("exit_code", 1)) is not int:
            raise WireError(f"{kind}: field 'exit_code'={d.get('exit_code')!r:.40} is not 1 or 2")
        _str_list(d, "late", kind)
    else:
        raise WireError(f"a node does not send '{kind}' on its control key")


def check_clock(kind: str, d: Mapping[str, Any]) -> None:
    """Raise WireError unless a clock message (start, abort, done) has its fields."""
    if kind == "start":
        _int(d, "n_steps", kind, required=True, low=1)
        h = d.get("h")
        if not isinstance(h, int | float) or isinstance(h, bool) or not math.isfinite(h) \
                or h <= 0:
            raise WireError(f"start: field 'h'={h!r:.40} is not a number > 0")
        _map(d, "info", kind, required=True)
        bad = [n for n, v in d["info"].items() if type(v) is not dict]
        if bad:
            raise WireError(f"start: the facts of {', '.join(map(str, bad[:3]))} are not maps")
    elif kind == "abort":
        if type(d.get("reason", "")) is not str:
            raise WireError("abort: field 'reason' is not a string")
    elif kind != "done":
        raise WireError(f"the clock does not send '{kind}'")


def check_start(d: Mapping[str, Any], n_steps: int | None = None, h: float | None = None,
                nodes: Iterable[str] = ()) -> None:
    """WireError unless ``start`` is well formed and of this run (steps, h, ``nodes``' facts)."""
    check_clock("start", d)
    if n_steps is not None and d["n_steps"] != n_steps:
        raise WireError(f"implausible start: n_steps={d['n_steps']}, the scenario has {n_steps}")
    if h is not None and d["h"] != h:
        raise WireError(f"implausible start: h={d['h']!r}, the scenario has {h!r}")
    missing = [n for n in nodes if n not in d["info"]]
    if missing:
        raise WireError(f"implausible start: no facts of {', '.join(missing)}")
