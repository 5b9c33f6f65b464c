"""The table's layout across a fork whose controller starts afresh (pure, no I/O).

A fork with another law (``suscosim run --fork RUN@T --set controller.law=...``) records the
parent's steps < k and its own steps >= k in one table, but the two laws may publish other
fields on ``controller/force`` (skyhook's ``c``, an MR law's current). The table's columns of
such a channel are the union of both: a field one law does not publish is NaN in its rows.

The recorder cannot know the new law's fields before its first message (step k), so it holds
the parent's records of that channel (:meth:`ForkLayouts.hold`) until then; its other
channels' rows wait for them in the table (memory by the fork's prefix, released at step k).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any


class ForkLayouts:
    """Which records a fork holds back, and the NaN-padded union layout of their channels."""

    def __init__(self, fresh_nodes: Iterable[str], start_k: int) -> None:
        self.fresh = frozenset(fresh_nodes)
        self.start_k = int(start_k)
        self.held: dict[str, list[tuple[int, float, Mapping[str, Any]]]] = {}
        self._fill: dict[str, dict[str, Any]] = {}

    def holds(self, node: str, k: int) -> bool:
        """A record of the parent's prefix (k < start) of a node that starts afresh."""
        return k < self.start_k and node in self.fresh

    def hold(self, name: str, k: int, t: float, d: Mapping[str, Any]) -> None:
        self.held.setdefault(name, []).append((k, t, d))

    def release(self, name: str, first: Mapping[str, Any]
                ) -> list[tuple[int, float, Mapping[str, Any]]]:
        """The held records of ``name`` padded to the union of their fields and those of the
        new node's ``first`` message (which :meth:`pad` pads from then on); ValueError when a
        field is a number in one and a list (or another length) in the other."""
        held = self.held.pop(name, [])
        shapes: dict[str, int | None] = {}
        for d in (*(d for _k, _t, d in held), first):
            for f, v in d.items():
                n = len(v) if type(v) is list else None
                if shapes.setdefault(f, n) != n:
                    raise ValueError(f"{name}: field {f!r} is {_shape(shapes[f])} in the parent "
                                     f"and {_shape(n)} in the fork")
        self._fill[name] = {f: float("nan") if n is None else [float("nan")] * n
                            for f, n in shapes.items()}
        return [(k, t, self.pad(name, d)) for k, t, d in held]

    def pad(self, name: str, d: Mapping[str, Any]) -> Mapping[str, Any]:
        """``d`` with the union's missing fields as NaN (``d`` itself for other channels)."""
        fill = self._fill.get(name)
        if fill is None or len(d) == len(fill):
            return d
        return {**fill, **d}


def _shape(n: int | None) -> str:
    return "a number" if n is None else f"a list of {n}"
