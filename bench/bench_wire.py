"""What the wire costs per message and per coupled step, in one warm process (issue #28 item 1).

    python bench/bench_wire.py [--n 20000]

Three tables, microseconds per call (the median of five ``timeit`` rounds of ``--n`` calls):

1. **The codec against its alternative**: the run's codec (:mod:`cosim.wire`: msgspec,
   compiled; a data message decoded into a typed struct and its numbers bounded by the
   channel's schema in C) against ``msgpack`` with the same checks written in Python (version,
   kind, ``k >= 0``, ``t >= 0``, every declared field a finite number within the channel's
   limit, the non-negative fields), on the plant's ``state`` and its 16-field ``arm`` message
   of the Chapter 6 corner (the null chain's payloads, bench/null_chain_nodes.py).
2. **Signing**: keyed BLAKE2b sign and verify (:class:`cosim.auth.RunKey`) of the plant's
   step message (its ``state``, held ``response`` and ``arm``: one bus message a step).
3. **A coupled step's protocol work**: the plant's (encode and check ``state``, ``response``
   and ``arm``, the step encoded and signed; verify and decode each force node's step and its
   ``force``) and a force node's (verify and decode the plant's step and its ``state``;
   encode, check, sign its own), without the bus.

In the null chain (bench/bench_null_chain.py) the same work costs two to three times as much:
there the code runs cold after every switch between processes (docs/cosim.md, "Issue #28
closed"). Timing lives here and in the docs, never in tests.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import timeit
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import msgpack  # noqa: E402
from null_chain_nodes import ARM, FORCE, RESPONSE, STATE  # noqa: E402

from cosim import schema  # noqa: E402
from cosim.auth import RunKey  # noqa: E402
from cosim.errors import WireError  # noqa: E402
from cosim.wire import SCHEMA_VERSION, codec, decode, encode, encode_step, inner  # noqa: E402


def msgpack_checked(node: str, channel: str) -> Callable[[bytes], dict[str, Any]]:
    """The alternative to :class:`cosim.wire.ChannelCodec`: msgpack, then the same checks in
    Python. Raises :class:`WireError` as the codec does."""
    spec = schema.channel(node, channel)
    assert spec is not None, f"{node}/{channel} is not in the schema"
    limit, declared = spec.limit, tuple(f.name for f in spec.fields)
    nonneg = schema.nonneg_fields(node, channel)

    def finite(x: Any) -> bool:
        return isinstance(x, (int, float)) and not isinstance(x, bool) and -limit <= x <= limit

    def check(raw: bytes) -> dict[str, Any]:
        m = msgpack.unpackb(raw)
        if not isinstance(m, dict) or m.get("v") != SCHEMA_VERSION or m.get("kind") != "data":
            raise WireError("not a data message of this version")
        k, t, d = m.get("k"), m.get("t"), m.get("d")
        if not isinstance(k, int) or k < 0 or not isinstance(t, float) or not t >= 0 \
                or not isinstance(d, dict):
            raise WireError("bad k, t or payload")
        for name in declared:
            if name in d:
                v = d[name]
                if not all(finite(x) for x in (v if isinstance(v, list) else (v,))):
                    raise WireError(f"field {name!r} out of bounds")
                if name in nonneg and min(v if isinstance(v, list) else (v,)) < 0:
                    raise WireError(f"field {name!r} negative")
        return d

    return check


def _us(fn: Callable[[], Any], n: int) -> float:
    return statistics.median(timeit.repeat(fn, number=n, repeat=5)) / n * 1e6


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=20000, help="calls per timeit round")
    n = ap.parse_args().n

    key = RunKey(os.urandom(32), os.urandom(16))
    st, rs, ar = (encode("data", 5, 0.005, d) for d in (STATE, RESPONSE, ARM))
    force = {name: encode("data", 5, 0.005, d) for name, d in FORCE.items()}
    plant_kx = "suscosim/run/plant/step"
    sign_plant = key.signer(plant_kx)
    plant_step = sign_plant(encode_step(5, 0.005, [("response", rs), ("arm", ar), ("state", st)]))
    force_kx = {name: f"suscosim/run/{name}/step" for name in FORCE}
    signers = {name: key.signer(kx) for name, kx in force_kx.items()}
    force_steps = {name: signers[name](encode_step(5, 0.005, [("force", force[name])]))
                   for name in FORCE}

    print(f"per call, us (median of 5 rounds of {n}); Python {sys.version.split()[0]}\n")
    print("| message | encode (msgspec) | decode + checks (msgspec, C) | "
          "decode + checks (msgpack, Python) |")
    print("|---|---|---|---|")
    for chan, data, raw in (("state", STATE, st), ("arm", ARM, ar)):
        ours, theirs = codec(f"plant/{chan}"), msgpack_checked("plant", chan)
        assert ours.decode(raw).d == theirs(raw)  # the two agree on what they accept
        print(f"| plant/{chan} ({len(data)} fields, {len(raw)} B) "
              f"| {_us(lambda d=data: encode('data', 5, 0.005, d), n):.2f} "
              f"| {_us(lambda c=ours, r=raw: c.decode(r), n):.2f} "
              f"| {_us(lambda c=theirs, r=raw: c(r), n):.2f} |")
    bad = encode("data", 5, 0.005, {**STATE, "z_w": math.nan})  # both must refuse it
    for check in (codec("plant/state").decode, msgpack_checked("plant", "state")):
        try:
            check(bad)
        except WireError:
            continue
        raise SystemExit(f"{check} took a NaN: the comparison is not like for like")

    print(f"\n| signing (the plant's step, {len(plant_step)} B) | us |\n|---|---|")
    body = encode_step(5, 0.005, [("response", rs), ("arm", ar), ("state", st)])
    print(f"| sign | {_us(lambda: sign_plant(body), n):.2f} |")
    print(f"| verify | {_us(lambda: key.verify(plant_kx, plant_step), n):.2f} |")

    def plant_step_work() -> None:
        for chan, data in (("state", STATE), ("response", RESPONSE), ("arm", ARM)):
            codec(f"plant/{chan}").decode(encode("data", 5, 0.005, data))
        sign_plant(encode_step(5, 0.005, [("response", rs), ("arm", ar), ("state", st)]))
        for name, raw in force_steps.items():
            for chan, one in inner(decode(key.verify(force_kx[name], raw))):
                codec(f"{name}/{chan}").decode(one)

    def force_step_work() -> None:
        for chan, one in inner(decode(key.verify(plant_kx, plant_step))):
            if chan == "state":
                codec("plant/state").decode(one)
        raw = encode("data", 5, 0.005, FORCE["tyre_road"])
        codec("tyre_road/force").decode(raw)
        signers["tyre_road"](encode_step(5, 0.005, [("force", raw)]))

    print("\n| a coupled step's protocol work, warm, without the bus | us |\n|---|---|")
    print(f"| plant | {_us(plant_step_work, n):.2f} |")
    print(f"| force node (tyre_road) | {_us(force_step_work, n):.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
