"""The whole-journal table builder the streamed one replaced (:mod:`cosim.table_writer`),
kept as its test oracle: every message held, then the rows every channel gave."""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable
from typing import Any

import numpy as np

from cosim.errors import WireError
from cosim.table_writer import _shape_verdicts  # the shape rule: one definition
from cosim.wire import Message, decode

Table = dict[str, np.ndarray]


def build_table(records: Iterable[tuple[str, bytes]]) -> tuple[Table, int]:
    """(table, records left out as bad) of the data records. A channel's fields are those
    most of its messages carry; per step the first message that carries them all is used (a
    stray or forged message cannot displace the real one)."""
    per_channel: dict[str, list[Message]] = {}
    bad = 0
    for channel, payload in records:
        try:
            msg = decode(payload)
        except WireError:
            bad += 1
            continue
        if msg.kind == "data" and msg.k >= 0:
            per_channel.setdefault(channel, []).append(msg)
    rows: dict[str, dict[int, dict[str, Any]]] = {}
    fields_of: dict[str, tuple[str, ...]] = {}
    times: dict[int, float] = {}
    for channel, msgs in per_channel.items():
        fields = Counter(tuple(sorted(m.d)) for m in msgs).most_common(1)[0][0]
        fields_of[channel] = fields
        # A message's shape: its field names and value types, in its own order. A producer
        # sends one shape, so a channel has a handful: each is judged once, not each message.
        shapes = [(tuple(m.d), tuple(map(type, m.d.values()))) for m in msgs]
        verdict = _shape_verdicts(Counter(shapes), fields)
        box = rows.setdefault(channel, {})
        for m, shape in zip(msgs, shapes, strict=True):
            if m.k in box or not verdict[shape]:
                bad += 1
                continue
            box[m.k] = m.d
            times.setdefault(m.k, m.t)
    if not rows:
        return {"k": np.zeros(0, dtype=int), "t": np.zeros(0)}, bad
    ks = sorted(set.intersection(*(set(v) for v in rows.values())))
    table: Table = {"k": np.asarray(ks, dtype=np.int64),
                    "t": np.asarray([times[k] for k in ks], dtype=float)}
    for channel in sorted(rows):
        box = rows[channel]
        for name in fields_of[channel]:
            arr = np.asarray([box[k][name] for k in ks], dtype=float)
            if arr.ndim == 2:
                for i in range(arr.shape[1]):
                    table[f"{channel}/{name}[{i}]"] = arr[:, i]
            else:
                table[f"{channel}/{name}"] = arr
    return table, bad
