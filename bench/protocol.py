"""The protocol's cost per message: the wire and message authentication. Timing is measured
here, never asserted in tests.

    python -m bench wire [--n 20000]
    python -m bench auth [--pairs 5] [--t-end 4.0] [--rev HEAD]


``wire`` (issue #28 item 1): microseconds per call in one warm process (median of five
``timeit`` rounds of ``--n``): (1) the run's codec (:mod:`cosim.wire`, msgspec, bounds checked
in C) against msgpack with the same checks in Python, on the plant's ``state`` and 16-field
``arm`` (the null chain's payloads, bench/null_chain_nodes.py; both must refuse NaN); (2)
keyed BLAKE2b sign and verify
(:class:`cosim.auth.RunKey`) of the plant's step message; (3) a coupled step's protocol work of
the plant and of a force node without the bus. In the null chain the same work costs two to


``auth`` (issue #15 item 4): (1) sign and verify of a quarter-car ``plant/state`` against its
encode and decode [us]; (2) coupled steps/s of the Chapter 3 quarter car
(``scenarios/ch3_step_quarter_car.toml``, distributed) from two copies of the tree (``git
archive REV``): A as it is, B with :class:`cosim.auth.RunKey` replaced by one that neither
signs nor verifies, run A B B A ... so that a drift of the machine hits both; each pair and the
median ratio printed. A failed run's folder is kept and named.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
import timeit
from collections.abc import Callable
from io import BytesIO
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import msgpack  # noqa: E402

from bench.null_chain_nodes import ARM, FORCE, RESPONSE, STATE  # noqa: E402
from cosim import schema  # noqa: E402
from cosim.auth import RunKey  # noqa: E402
from cosim.errors import WireError  # noqa: E402
from cosim.wire import SCHEMA_VERSION, codec, decode, encode, encode_step, inner  # noqa: E402


# ---- wire -----------------------------------------------------------------------------------
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


def wire(args: argparse.Namespace) -> int:
    """``wire``: the codec, signing and a coupled step's protocol work [us per call]."""
    n = args.n
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


# ---- auth -----------------------------------------------------------------------------------
AUTH_SCENARIO = "scenarios/ch3_step_quarter_car.toml"


def per_message(n: int = 200_000) -> dict[str, float]:
    """Sign, verify, encode and decode of one quarter-car state message [us each]."""
    # (ROOT is on sys.path)
    from cosim.auth import RunKey, derive_run_key
    from cosim.wire import decode, encode

    key = RunKey(derive_run_key(b"bench" * 8, "bench"))
    where = "suscosim/bench/plant/state"
    body = encode("data", 1234, 1.234, {"z_b": 0.01, "v_b": 0.1, "z_w": 0.02, "v_w": 0.2})
    sign = key.signer(where)
    raw = sign(body)
    us = {name: 1e6 * min(timeit.repeat(fn, number=n, repeat=3)) / n for name, fn in (
        ("sign", lambda: sign(body)), ("verify", lambda: key.verify(where, raw)),
        ("encode", lambda: encode("data", 1234, 1.234, {"z_b": 0.01, "v_b": 0.1,
                                                        "z_w": 0.02, "v_w": 0.2})),
        ("decode", lambda: decode(body)))}
    us["bytes"] = float(len(body))
    return us


NO_AUTH = '''

class RunKey:  # bench/protocol.py auth: the same code without signing or verifying
    def __init__(self, key: bytes) -> None:
        self.key = key

    def sign(self, keyexpr: str, body: bytes) -> bytes:
        return body

    def signer(self, keyexpr: str):
        return lambda body: body

    def verify(self, keyexpr: str, raw: bytes) -> bytes:
        return raw
'''


def tree(rev: str, into: Path, auth: bool) -> Path:
    """``git archive REV`` unpacked under ``into``; without ``auth`` RunKey does nothing."""
    blob = subprocess.run(["git", "-C", str(ROOT), "archive", rev], check=True,
                          capture_output=True).stdout
    with tarfile.open(fileobj=BytesIO(blob)) as tar:
        tar.extractall(into, filter="data")
    if not auth:
        with open(into / "cosim" / "auth.py", "a") as f:
            f.write(NO_AUTH)
    return into


def one_run(tree: Path, out: Path, t_end: float) -> float:
    """Coupled steps/s of one distributed run of the Chapter 3 scenario from ``tree``."""
    env = {"PYTHONPATH": str(tree), "PATH": "/usr/bin:/bin", "HOME": str(Path.home())}
    res = subprocess.run([sys.executable, "-m", "orchestrator", "run", AUTH_SCENARIO, "--quiet",
                          "--out", str(out), "--set", f"run.t_end={t_end}"],
                         cwd=tree, env=env, capture_output=True, text=True, timeout=600)
    if res.returncode != 0:
        kept = Path(tempfile.mkdtemp(prefix="bench_auth_failed_"))
        subprocess.run(["cp", "-r", str(out), str(kept)], check=False)
        print(f"run failed in {tree} (folder kept in {kept}): {res.stderr.strip()}")
        return float("nan")
    return float(json.loads((out / "summary.json").read_text())["steps_per_s"])


def auth(args: argparse.Namespace) -> int:
    """``auth``: sign/verify per message, and steps/s with and without authentication."""
    us = per_message()
    print(f"per message ({us['bytes']:.0f} B + 20 B signature field): "
          f"sign {us['sign']:.2f} us, "
          f"verify {us['verify']:.2f} us; encode {us['encode']:.2f} us, "
          f"decode {us['decode']:.2f} us")
    with tempfile.TemporaryDirectory() as tmp:
        with_auth = tree(args.rev, Path(tmp) / "auth", True)
        without = tree(args.rev, Path(tmp) / "noauth", False)
        rows = []
        for i in range(args.pairs):
            if i % 2:  # alternate which goes first: a pair's first run must not bias it
                b = one_run(without, Path(tmp) / f"b{i}", args.t_end)
                a = one_run(with_auth, Path(tmp) / f"a{i}", args.t_end)
            else:
                a = one_run(with_auth, Path(tmp) / f"a{i}", args.t_end)
                b = one_run(without, Path(tmp) / f"b{i}", args.t_end)
            print(f"pair {i + 1}: authenticated {a:7.0f} steps/s, without {b:7.0f} steps/s, "
                  f"ratio {a / b:.3f}", flush=True)
            if a == a and b == b:  # neither failed
                rows.append((a, b))
    if not rows:
        return 1
    ratios = [a / b for a, b in rows]
    print(f"median: authenticated {statistics.median(a for a, _ in rows):.0f} steps/s, "
          f"without {statistics.median(b for _, b in rows):.0f} steps/s, "
          f"ratio {statistics.median(ratios):.3f} (min {min(ratios):.3f}, "
          f"max {max(ratios):.3f})")
    return 0



def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("wire", help="the codec, signing and a step's protocol work [us]")
    p.add_argument("--n", type=int, default=20000, help="calls per timeit round")
    p.set_defaults(fn=wire)
    p = sub.add_parser("auth", help="message authentication: per message and per run")
    p.add_argument("--pairs", type=int, default=5)
    p.add_argument("--rev", default="HEAD", help="the revision to measure")
    p.add_argument("--t-end", type=float, default=4.0, help="simulated time [s]")
    p.set_defaults(fn=auth)
    args = ap.parse_args(argv)
    return int(args.fn(args) or 0)


if __name__ == "__main__":
    raise SystemExit(main())
