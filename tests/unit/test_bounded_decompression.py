"""#46 item 2: a compressed input is inflated within bounds: a journal segment whose zstd
frame declares 2 GiB is refused by `suscosim export`, an FMU holding 2 GiB of zeros by
`suscosim check` and `run` from its zip directory (exit 2, under 300 MB, nothing left in
$TMPDIR)."""

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


def _peak_child_rss_mb(cmd: list[str], env: dict[str, str] | None = None
                       ) -> tuple[int, float, str]:
    """(exit code, peak RSS [MB], stderr) of ``cmd`` run from a fresh Python process, so
    RUSAGE_CHILDREN holds that one child only."""
    probe = ("import json, resource, subprocess, sys\n"
             "r = subprocess.run(sys.argv[1:], capture_output=True, text=True, timeout=120)\n"
             "rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss\n"
             "print(json.dumps([r.returncode, rss / 1024, r.stderr]))\n")
    env = env or dict(os.environ, PYTHONPATH=str(ROOT))
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


def _fmu_bomb(path: Path) -> None:
    """A zip with a model description and 2 GiB of zeros (9 MB deflated at level 1), written in
    1 MiB pieces."""
    import zipfile

    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as zf:
        zf.writestr("modelDescription.xml", b'<?xml version="1.0"?>\n<fmiModelDescription '
                    b'fmiVersion="2.0" modelName="m" guid="{0}"/>\n')
        zero = bytes(1 << 20)
        with zf.open("resources/zeros.bin", "w", force_zip64=True) as fh:
            for _ in range(BOMB_RAW >> 20):
                fh.write(zero)


def test_an_fmu_of_2_gib_of_zeros_is_refused_from_its_directory(tmp_path: Path) -> None:
    bomb = tmp_path / "bomb.fmu"
    _fmu_bomb(bomb)
    assert bomb.stat().st_size < 10 << 20
    tmpdir = tmp_path / "tmpdir"
    tmpdir.mkdir()
    scenario = ROOT / "scenarios" / "ch5_qvm_tss1_random.toml"
    for command in ("check", "run"):
        cmd = [sys.executable, "-m", "orchestrator", command, str(scenario),
               "--set", f'controller={{ law = "fmu", fmu = "{bomb}" }}']
        if command == "run":
            cmd += ["--mode", "monolithic", "--quiet", "--out", str(tmp_path / "run")]
        env = dict(os.environ, PYTHONPATH=str(ROOT), TMPDIR=str(tmpdir))
        rc, peak_mb, err = _peak_child_rss_mb(cmd, env)
        last = err.strip().splitlines()[-1]
        assert rc == 2 and "bomb.fmu" in last and "zip bomb" in last, err
        assert peak_mb < 300, f"{command}: peak RSS {peak_mb:.0f} MB"
        assert os.listdir(tmpdir) == [], f"{command} left {os.listdir(tmpdir)} in $TMPDIR"
