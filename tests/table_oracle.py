"""The whole-journal table builder the streamed one replaced (:mod:`cosim.table_writer`),
kept as its test oracle: every message held, then the rows every channel gave."""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable
from typing import Any

import numpy as np

from cosim.errors import WireError
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


_Shape = tuple[tuple[str, ...], tuple[type, ...]]


def _shape_verdicts(counts: Counter[_Shape], fields: tuple[str, ...]) -> dict[_Shape, bool]:
    """Whether a message of each shape goes in the table: it carries every one of the
    channel's ``fields``, each a list or not as in the channel's most common such shape."""
    def listness(shape: _Shape) -> dict[str, bool] | None:
        kinds = dict(zip(*shape, strict=True))
        if not all(f in kinds for f in fields):
            return None
        return {f: kinds[f] is list for f in fields}

    complete = [(n, shape) for shape, n in counts.items() if listness(shape) is not None]
    ref = listness(max(complete, key=lambda c: c[0])[1]) if complete else None
    return {shape: ref is not None and listness(shape) == ref for shape in counts}
