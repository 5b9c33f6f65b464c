"""Load blocks: the live fatigue node's blocks of plant steps (:class:`StepBlocks`), and the
recorder's ``recorder/loads`` relay (:class:`LoadStreamer`, :func:`wire_pieces`: kept while
the recorder still publishes it; the fatigue node reads ``plant/arm`` itself now).

A block is consecutive steps of the load channel (``plant/arm``, :data:`cosim.channels.
LOAD_CHANNEL`) as one bus message on ``recorder/loads``: ``{"k0": first step, "t": [s],
"<field>": [value per step], ...}`` with the message's ``k`` the block's last step. Steps
come in order and without gaps (``k0`` of a block is the last block's ``k`` + 1); a field's
list has one value per time. Loads are in N (forces) and N·m (the torsion-spring moment),
as the plant publishes them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .wire import MAX_MESSAGE_BYTES

META = ("k0", "t")
"""The keys of a block that are not load fields."""


class StepBlocks:
    """Consecutive steps of the load channel gathered into blocks of ``block_steps`` rows.

    :meth:`add` takes one step's time [s] and fields (the message's payload: every number
    field is a load column, in the first step's order; a later step must have them all);
    :attr:`full` says a block is complete; :meth:`take` returns (t (n,), loads (n, fields))
    and starts the next block. Steps are taken in the order given (the caller checks it).
    """

    def __init__(self, block_steps: int) -> None:
        self.block_steps = max(1, int(block_steps))
        self.fields: list[str] = []
        self._t: list[float] = []
        self._rows: list[list[float]] = []

    def add(self, t: float, d: dict[str, Any]) -> None:
        """One step; a ValueError names a missing or non-numeric field."""
        if not self.fields:
            self.fields = [f for f, v in d.items()
                           if f not in META and type(v) in (int, float)]
            if not self.fields:
                raise ValueError("no load field (numbers) in the step")
        try:
            row = [float(d[f]) for f in self.fields]
        except KeyError as exc:
            raise ValueError(f"no field {exc}") from None
        except (TypeError, ValueError) as exc:
            raise ValueError(f"a field is not a number ({exc})") from None
        self._t.append(float(t))
        self._rows.append(row)

    @property
    def full(self) -> bool:
        return len(self._t) >= self.block_steps

    def __len__(self) -> int:
        return len(self._t)

    def take(self) -> tuple[np.ndarray, np.ndarray]:
        """(t [s] (n,), loads (n, len(fields))) of the steps gathered; starts a new block."""
        t = np.asarray(self._t, dtype=float)
        loads = np.asarray(self._rows, dtype=float).reshape(t.size, len(self.fields))
        self._t, self._rows = [], []
        return t, loads


class LoadStreamer:
    """Cuts the load channel into consecutive blocks as its steps arrive (in any order)."""

    def __init__(self, block_steps: int) -> None:
        self.block_steps = max(1, int(block_steps))
        self.pending: dict[int, tuple[float, dict[str, Any]]] = {}
        self.next_k = 0

    def add(self, k: int, t: float, fields: dict[str, Any]) -> None:
        """Keep the first message of each step (as the table does), from next_k on."""
        if k >= self.next_k and k not in self.pending:
            self.pending[k] = (t, fields)

    def blocks(self, last_k: int | None) -> list[dict[str, Any]]:
        """Full blocks available now; with ``last_k`` (the run's last step) also the final
        partial block once every step up to it is there."""
        out: list[dict[str, Any]] = []
        while True:
            n = 0
            while self.next_k + n in self.pending and n < self.block_steps:
                n += 1
            final = last_k is not None and n > 0 and self.next_k + n - 1 == last_k
            if n < self.block_steps and not final:
                return out
            ks = range(self.next_k, self.next_k + n)
            rows = [self.pending.pop(k) for k in ks]
            names = [f for f in rows[0][1] if f not in META]
            block: dict[str, Any] = {"k0": self.next_k, "t": [r[0] for r in rows]}
            for f in names:
                block[f] = [float(r[1].get(f, float("nan"))) for r in rows]
            out.append(block)
            self.next_k += n


def wire_pieces(blk: dict[str, Any], max_bytes: int = MAX_MESSAGE_BYTES - 2048
                ) -> list[dict[str, Any]]:
    """A load block cut into consecutive pieces that each fit one bus message (a msgpack
    float is 9 bytes); the fatigue worker takes blocks of any length."""
    n = len(blk["t"])
    fields = [f for f in blk if f != "k0"]
    per = max(1, max_bytes // (9 * len(fields) + 16))
    if n <= per:
        return [blk]
    return [{"k0": blk["k0"] + i, **{f: blk[f][i:i + per] for f in fields}}
            for i in range(0, n, per)]


def block_loads(d: dict[str, Any], fields: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """(t [s], loads: one column per name of ``fields``, one row per step) of block ``d``;
    a ValueError names what is wrong (a missing field, a ragged or non-numeric list)."""
    t = np.asarray(d.get("t", ()), dtype=float)
    try:
        loads = np.column_stack([np.asarray(d[f], dtype=float) for f in fields])
    except KeyError as exc:
        raise ValueError(f"no field {exc}") from None
    except ValueError as exc:
        raise ValueError(f"ValueError: {exc}") from None
    if loads.shape[0] != t.size:
        raise ValueError(f"{loads.shape[0]} rows for {t.size} times")
    return t, loads


def load_fields(d: dict[str, Any]) -> list[str]:
    """The load fields of block ``d``, in its order."""
    return [f for f in d if f not in META]
