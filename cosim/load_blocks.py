"""The live fatigue node's blocks of consecutive plant steps of the load channel
(``plant/arm``), in N (forces) and N·m (the torsion-spring moment)."""

from __future__ import annotations

from typing import Any

import numpy as np

META = ("k0", "t")  # the keys of a block that are not load fields


class StepBlocks:
    """Consecutive steps gathered into blocks of ``block_steps`` rows: every number field of
    the first step is a load column, in its order (a later step must have them all)."""

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
