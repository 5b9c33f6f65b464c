"""What message authentication costs (issue #15 item 4): coupled steps/s with and without it.

Two measurements:

1. **Per message**: keyed BLAKE2b sign and verify of a typical data message (``plant/state``
   of the quarter car), against the encode + decode every message already costs [us].
2. **Per run**: the Chapter 3 quarter car (``scenarios/ch3_step_quarter_car.toml``,
   distributed, 4001 steps) run in turn with two copies of the committed tree (``git
   archive HEAD``): A as it is (every message signed and verified), B the same with
   :class:`cosim.auth.RunKey` replaced by one that neither signs nor verifies (the only
   difference), A B B A A B ..., so that a drift of the machine's speed hits both alike. It
   prints each run's ``steps_per_s`` (summary.json: coupled steps per second of the step
   loop) and the median ratio of the pairs.

Usage::

    python3 bench/bench_auth.py [--pairs 5] [--t-end 4.0] [--rev HEAD]

Timing is measured here, never asserted in tests. Both trees use the same Python and
packages; a failed run's folder is kept and named.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tarfile
import tempfile
import timeit
from io import BytesIO
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = "scenarios/ch3_step_quarter_car.toml"


def per_message(n: int = 200_000) -> dict[str, float]:
    """Sign, verify, encode and decode of one quarter-car state message [us each]."""
    sys.path.insert(0, str(ROOT))
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

class RunKey:  # bench/bench_auth.py: the same code without signing or verifying
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
    res = subprocess.run([sys.executable, "-m", "orchestrator", "run", SCENARIO, "--quiet",
                          "--out", str(out), "--set", f"run.t_end={t_end}"],
                         cwd=tree, env=env, capture_output=True, text=True, timeout=600)
    if res.returncode != 0:
        kept = Path(tempfile.mkdtemp(prefix="bench_auth_failed_"))
        subprocess.run(["cp", "-r", str(out), str(kept)], check=False)
        print(f"run failed in {tree} (folder kept in {kept}): {res.stderr.strip()}")
        return float("nan")
    return float(json.loads((out / "summary.json").read_text())["steps_per_s"])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument("--rev", default="HEAD", help="the revision to measure")
    ap.add_argument("--t-end", type=float, default=4.0, help="simulated time [s]")
    args = ap.parse_args(argv)
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


if __name__ == "__main__":
    sys.exit(main())
