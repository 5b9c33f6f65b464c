"""#46 item 2: a compressed input is inflated within bounds: a journal segment whose zstd
frame declares 2 GiB is refused by `suscosim export` (exit 2) in well under 300 MB."""

from __future__ import annotations

import json
import os
import struct
import subprocess
import sys
import zlib
from pathlib import Path

import msgpack
import pytest

from cosim import journal as jn
from tests.conftest import ROOT

BOMB_RAW = 2 << 30  # 2 GiB of zeros: ~65 kB as one zstd frame


def _zstd_zeros(n: int) -> bytes:
    import zstandard

    co = zstandard.ZstdCompressor(level=1, write_checksum=True).compressobj(size=n)
    zero = bytes(1 << 20)
    return b"".join(co.compress(zero) for _ in range(n >> 20)) + co.flush()


def _segment(body: bytes, rawlen: int, nrec: int = 1, first: int = 0) -> bytes:
    head = jn._SEG.pack(jn.SEG_MAGIC, len(body), rawlen, nrec, first)
    return b"".join((head, struct.pack("<I", zlib.crc32(head)), body,
                     struct.pack("<I", zlib.crc32(body))))


def _peak_child_rss_mb(cmd: list[str]) -> tuple[int, float, str]:
    """(exit code, peak RSS [MB], stderr) of ``cmd`` run from a fresh Python process, so
    RUSAGE_CHILDREN holds that one child only."""
    probe = ("import json, resource, subprocess, sys\n"
             "r = subprocess.run(sys.argv[1:], capture_output=True, text=True, timeout=120)\n"
             "rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss\n"
             "print(json.dumps([r.returncode, rss / 1024, r.stderr]))\n")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-c", probe, *cmd], capture_output=True, text=True,
                         timeout=180, env=env, cwd=ROOT)
    rc, mb, err = json.loads(out.stdout)
    return int(rc), float(mb), str(err)


@pytest.fixture(scope="module")
def bomb_body() -> bytes:
    return _zstd_zeros(BOMB_RAW)


def test_a_segment_declaring_2_gib_is_refused_by_the_reader(bomb_body: bytes) -> None:
    import zstandard

    dctx = zstandard.ZstdDecompressor()
    with pytest.raises(ValueError, match="more than"):
        jn._body_records(bomb_body, BOMB_RAW, 1, dctx)
    # a header that understates its body: the stream stops one byte past what it declares
    with pytest.raises(ValueError, match="decompresses to more than 4097 bytes"):
        jn._body_records(bomb_body, 4096, 1, dctx)
    good = msgpack.packb(["plant/x", b"\x00" * 8])
    body = zstandard.ZstdCompressor(write_checksum=True).compress(good)
    assert jn._body_records(body, len(good), 1, dctx) == [("plant/x", b"\x00" * 8)]


def test_export_of_a_journal_bomb_exits_2_in_bounded_memory(tmp_path: Path,
                                                           bomb_body: bytes) -> None:
    journal = tmp_path / "journal.msgpack"
    journal.write_bytes(msgpack.packb([jn.MAGIC, jn.VERSION, "bomb"]) +
                        _segment(bomb_body, BOMB_RAW))
    assert journal.stat().st_size < 70_000
    rc, peak_mb, err = _peak_child_rss_mb([sys.executable, "-m", "orchestrator", "export",
                                           str(journal), "--out", str(tmp_path / "out")])
    assert rc == 2, err
    assert str(journal) in err.strip().splitlines()[-1], err
    assert peak_mb < 300, f"peak RSS {peak_mb:.0f} MB"
