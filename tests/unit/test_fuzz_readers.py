"""Every reader of a file a user can hand the program, fuzzed with hypothesis (issue #43
item 4): a valid file of each kind, mutated (bytes flipped, cut, spliced, repeated) or
replaced by random bytes, goes into the reader. The only outcomes are a result or the
reader's named error (:class:`cosim.errors.SuscosimError`: an InputFileError naming the
file, or one it names, or a ScenarioError naming the key of the one file the command was
given); never another exception, never a hang (each case bounded by an alarm), never a file
written outside the case's folder.

Bounded: ``SUSCOSIM_FUZZ_EXAMPLES`` examples per reader (20 by default; a nightly run may
raise it), derandomized, no example database.
"""

from __future__ import annotations

import io
import os
import signal
import zipfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cosim import checkpoint as ck
from cosim import plaindata
from cosim.errors import InputFileError, ScenarioError, SuscosimError

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = int(os.environ.get("SUSCOSIM_FUZZ_EXAMPLES", "20"))
CASE_S = 20.0
"""The bound of one case [s] (an alarm): a reader that takes longer hangs."""
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                       HealthCheck.function_scoped_fixture])


@contextmanager
def _bounded(seconds: float = CASE_S) -> Iterator[None]:
    def alarm(signum: int, frame: Any) -> None:
        raise TimeoutError(f"a reader took more than {seconds:g} s (a hang)")

    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


@st.composite
def mutated(draw: Any, sample: bytes) -> bytes:
    """``sample`` with a few edits, or random bytes (one case in eight)."""
    if draw(st.integers(0, 7)) == 0:
        return draw(st.binary(max_size=512))
    data = bytearray(sample)
    for _ in range(draw(st.integers(1, 4))):
        op = draw(st.sampled_from(["flip", "cut", "splice", "repeat", "zero"]))
        if not data:
            break
        i = draw(st.integers(0, len(data) - 1))
        if op == "flip":
            data[i] ^= 1 << draw(st.integers(0, 7))
        elif op == "cut":
            del data[i:]
        elif op == "splice":
            data[i:i] = draw(st.binary(min_size=1, max_size=16))
        elif op == "repeat":
            j = draw(st.integers(i, min(len(data), i + 64)))
            data[i:i] = data[i:j] * draw(st.integers(1, 8))
        else:
            data[i:i + draw(st.integers(1, 16))] = b"\0" * 4
    return bytes(data)


_CASE = [0]


def _case_dir(tmp_path: Path) -> Path:
    _CASE[0] += 1
    d = tmp_path / f"case{_CASE[0]}"
    d.mkdir()
    return d


def _try(read: Callable[[Path], Any], path: Path, named: tuple[type, ...] = (SuscosimError,)
         ) -> None:
    """The reader on ``path``: a result or its named error naming the file; nothing written
    outside the case's folder (the working directory untouched)."""
    before = set(os.listdir("."))
    try:
        with _bounded():
            read(path)
    except ScenarioError as exc:  # a key of the file the command was given: names the key
        assert str(exc).startswith("scenario key '"), exc
    except InputFileError as exc:  # this file, or one it names (a duty's event scenario)
        assert exc.path and str(exc).startswith(exc.path), exc
    except named as exc:
        assert path.name in str(exc) or str(path) in str(exc), f"not named: {exc}"
    assert set(os.listdir(".")) == before
    assert os.listdir(path.parent) == [path.name]  # nothing beside the file either


def _fuzz_file(tmp_path: Path, name: str, sample: bytes, read: Callable[[Path], Any],
               named: tuple[type, ...] = (SuscosimError,), examples: int = EXAMPLES
               ) -> Callable[[], None]:
    @settings(FUZZ, max_examples=examples)
    @given(data=mutated(sample))
    def run(data: bytes) -> None:
        path = _case_dir(tmp_path) / name
        path.write_bytes(data)
        _try(read, path, named)

    return run


# ---- the samples --------------------------------------------------------------------------
def _channel_set() -> Any:
    from cosim.formats.channel_set import ChannelSet

    t = np.arange(8) * 0.01
    return ChannelSet(t, {"F_z": np.sin(t) * 1e3, "F_x": np.cos(t)}, {"F_z": "N", "F_x": "N"})


def _load_sample(tmp_path: Path, fmt: str, suffix: str) -> bytes:
    from cosim.formats.channel_set import write_channels

    path = tmp_path / f"sample{suffix}"
    write_channels(_channel_set(), path, fmt)
    return path.read_bytes()


# ---- text inputs ----------------------------------------------------------------------------
def test_fuzz_scenario_toml(tmp_path, monkeypatch):
    from cosim import scenario as sc

    monkeypatch.chdir(tmp_path)
    sample = (ROOT / "scenarios" / "ch3_step_quarter_car.toml").read_bytes()
    _fuzz_file(tmp_path, "scenario.toml", sample, sc.load)()


def test_fuzz_part_toml(tmp_path, monkeypatch):
    from nodes.fatigue.parts.schema import load_part

    monkeypatch.chdir(tmp_path)
    sample = (ROOT / "nodes" / "fatigue" / "parts" / "data" / "upper_arm.toml").read_bytes()
    _fuzz_file(tmp_path, "part.toml", sample, load_part)()


def test_fuzz_road_csv(tmp_path, monkeypatch):
    from nodes.tyre_road.measured import read_profile_csv

    monkeypatch.chdir(tmp_path)
    sample = b"# x, left, right\nx,z_l,z_r\n" + b"".join(
        f"{0.05 * i:.3f},{0.001 * (i % 7):.4f},{-0.001 * (i % 5):.4f}\n".encode()
        for i in range(40))
    _fuzz_file(tmp_path, "road.csv", sample, read_profile_csv)()


@pytest.mark.parametrize("kind", ["tir", "duty", "sweep"])
def test_fuzz_tyre_duty_and_sweep_files(tmp_path, monkeypatch, kind):
    from nodes.tyre_road.magic_formula import read_tir
    from orchestrator.duty import load_duty
    from orchestrator.sweep.spec import load_sweep

    monkeypatch.chdir(tmp_path)
    sample, read = {
        "tir": (ROOT / "nodes" / "tyre_road" / "tyres" / "mpv_215_65r16.tir", read_tir),
        "duty": (ROOT / "scenarios" / "duty" / "ch6_proving_ground.toml", load_duty),
        "sweep": (min((ROOT / "scenarios" / "doe").glob("*.toml")), load_sweep)}[kind]
    _fuzz_file(tmp_path, sample.name, sample.read_bytes(), read)()


def test_fuzz_frd(tmp_path, monkeypatch):
    from nodes.fatigue.parts.calculix import read_frd_stress

    monkeypatch.chdir(tmp_path)
    rec = "".join(f" -1{n:5d}" + "".join(f"{v:12.5E}" for v in (n, 2.0, 3.0, 0.5, 0.25, 1.5))
                  + "\n" for n in range(1, 6))
    sample = f"    1C\n -4  STRESS      6    1\n -5  SXX\n{rec} -3\n".encode()
    _fuzz_file(tmp_path, "part.frd", sample, read_frd_stress)()


# ---- binary and table inputs ------------------------------------------------------------------
@pytest.mark.parametrize("fmt,suffix", [("csv", ".csv"), ("parquet", ".parquet"),
                                        ("mdf4", ".mf4"), ("rpc3", ".rsp")])
def test_fuzz_load_files(tmp_path, monkeypatch, fmt, suffix):
    from cosim.formats.channel_set import read_channels

    monkeypatch.chdir(tmp_path)
    sample = _load_sample(tmp_path, fmt, suffix)
    _fuzz_file(tmp_path, f"loads{suffix}", sample, read_channels)()


@pytest.mark.parametrize("fmt", ["LDFI", "KDBI"])
def test_fuzz_opencrg(tmp_path, monkeypatch, fmt):
    import pyopencrg

    from nodes.tyre_road.measured import read_crg

    monkeypatch.chdir(tmp_path)
    u, v = np.arange(0, 4.0, 0.1), np.array([-1.0, 0.0, 1.0])
    path = tmp_path / "sample.crg"
    pyopencrg.CrgRoad(0.01 * np.sin(u)[:, None] * np.ones(v.size), u_inc=0.1, v=v).save(
        path, fmt=fmt)
    _fuzz_file(tmp_path, "road.crg", path.read_bytes(), read_crg)()


def test_fuzz_journal(tmp_path, monkeypatch):
    from cosim.journal import JournalWriter, read_journal

    monkeypatch.chdir(tmp_path)
    path = tmp_path / "sample.msgpack"
    w = JournalWriter(path, "fuzzrun")
    for k in range(30):
        w.append("plant/state", bytes([k % 256]) * 20)
        if k % 10 == 9:
            w.flush()
    w.close()
    _fuzz_file(tmp_path, "journal.msgpack", path.read_bytes(), read_journal)()


@pytest.mark.parametrize("suffix,fmt", [(".inp", "abaqus"), (".msh", "gmsh"),
                                        (".bdf", "nastran")])
def test_fuzz_meshes(tmp_path, monkeypatch, suffix, fmt):
    import meshio

    from nodes.fatigue.parts.mesh import read_mesh

    monkeypatch.chdir(tmp_path)
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1.0]])
    path = tmp_path / f"sample{suffix}"
    meshio.write(path, meshio.Mesh(pts, [("tetra", np.array([[0, 1, 2, 3], [1, 2, 3, 4]]))]),
                 file_format=fmt)
    _fuzz_file(tmp_path, f"part{suffix}", path.read_bytes(), read_mesh)()


def test_fuzz_ansys_rst(tmp_path, monkeypatch):
    from ansys.mapdl.reader import examples

    from nodes.fatigue.parts.ansys_rst import read_rst

    monkeypatch.chdir(tmp_path)
    sample = Path(examples.rstfile).read_bytes()
    _fuzz_file(tmp_path, "part.rst", sample, lambda p: read_rst(p, timeout=CASE_S / 2),
               examples=max(2, EXAMPLES // 8))()  # a child process each (~4 s)


# ---- checkpoints ------------------------------------------------------------------------------
STATE = {"q": np.arange(6, dtype=float), "n": 3, "big": 2**100, "t": (1, 2.5, "x"),
         "rng": np.random.default_rng(1), "s": {1, 2}, "c": 1 + 2j, "b": b"\0\1"}


@FUZZ
@given(data=mutated(plaindata.encode(STATE)))
def test_fuzz_plain_data_decoding(data: bytes):
    with _bounded():
        try:
            plaindata.decode(data)
        except plaindata.PlainDataError:
            pass


def test_fuzz_checkpoint_files(tmp_path):
    key = ck.checkpoint_key(b"k" * 32)
    scen = {"run": {"h": 0.001}}
    ck.write_node_state(tmp_path, 5, "plant", STATE, key)
    ck.write_manifest(tmp_path, 5, 0.005, scen, {"plant": {
        "file": "plant.ckpt", "sha256": "0" * 64, "bytes": 0}}, key)
    node_file = ck.step_folder(tmp_path, 5) / "plant.ckpt"
    manifest = ck.step_folder(tmp_path, 5) / ck.MANIFEST
    good = {p: p.read_bytes() for p in (node_file, manifest)}

    @FUZZ
    @given(which=st.sampled_from(sorted(good)), data=st.data())
    def run(which: Path, data: Any) -> None:
        for p, b in good.items():
            p.write_bytes(b)
        which.write_bytes(data.draw(mutated(good[which])))
        with _bounded():
            try:
                ck.load_for_resume(tmp_path, scen, key=key)
            except ck.CheckpointError as exc:
                assert "checkpoint" in str(exc) or str(tmp_path) in str(exc), exc

    run()


# ---- an FMU is a zip --------------------------------------------------------------------------
def _zip(members: dict[str, bytes], method: int = zipfile.ZIP_DEFLATED) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", method) as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    return buf.getvalue()


MD = (b'<?xml version="1.0" encoding="UTF-8"?>\n<fmiModelDescription fmiVersion="2.0" '
      b'modelName="m" guid="{0}"><CoSimulation modelIdentifier="m"/><ModelVariables>'
      b'<ScalarVariable name="u" valueReference="0" causality="input" variability='
      b'"continuous"><Real start="0"/></ScalarVariable></ModelVariables><ModelStructure/>'
      b'</fmiModelDescription>\n')


@pytest.mark.parametrize("members,why", [
    ({"binaries/linux64/m.so": b"\0"}, "no modelDescription.xml"),
    ({"modelDescription.xml": MD, "../../evil.so": b"\0"}, "outside"),
    ({"modelDescription.xml": MD, "/abs/evil.so": b"\0"}, "outside"),
    ({"modelDescription.xml": MD, "binaries\\..\\..\\evil.so": b"\0"}, "outside"),
    ({"modelDescription.xml": MD, "resources/bomb.bin": b"\0" * (64 << 20)}, "zip bomb"),
])
def test_fuzz_fmu_zip_refusals_are_named(tmp_path, monkeypatch, members, why):
    from nodes.controller.fmu import _read_description

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("nodes.controller.fmu.MAX_FMU_BYTES", 32 << 20)
    path = tmp_path / "law.fmu"
    path.write_bytes(_zip(members))
    with _bounded(), pytest.raises(SuscosimError, match=why) as e:
        _read_description(path)
    assert "law.fmu" in str(e.value)
    assert sorted(os.listdir(tmp_path)) == ["law.fmu"]


@FUZZ
@given(names=st.lists(st.text(min_size=1, max_size=12), max_size=4), data=st.data())
def test_fuzz_fmu_zip(tmp_path_factory, names, data):
    from nodes.controller.fmu import _read_description

    d = tmp_path_factory.mktemp("fmu")
    members = {"modelDescription.xml": MD, **{n: b"x" for n in names}}
    try:
        sample = _zip(members)
    except (ValueError, UnicodeEncodeError, IndexError):
        return  # a name zipfile itself refuses to write
    path = d / "law.fmu"
    path.write_bytes(data.draw(mutated(sample)))
    _try(_read_description, path)


# ---- through the CLI: exit 2 named, never 1 ---------------------------------------------------
@pytest.mark.parametrize("command", ["check", "export"])
def test_fuzz_cli_exit_codes(tmp_path, command):
    """A few mutated files through ``suscosim check`` (a scenario) and ``suscosim export``
    (a journal): exit 0 or 2, never an internal error (a subprocess each, so few cases)."""
    from cosim.journal import JournalWriter

    from ..conftest import suscosim

    if command == "check":
        sample, name = (ROOT / "scenarios" / "ch3_step_quarter_car.toml").read_bytes(), "s.toml"
    else:
        path = tmp_path / "sample.msgpack"
        w = JournalWriter(path, "fuzzrun")
        w.append("plant/state", b"\x85")
        w.close()
        sample, name = path.read_bytes(), "journal.msgpack"

    @settings(FUZZ, max_examples=max(3, EXAMPLES // 6))
    @given(data=mutated(sample))
    def run(data: bytes) -> None:
        d = _case_dir(tmp_path)
        (d / name).write_bytes(data)
        args = [str(d / name)] + (["--out", str(d / "out")] if command == "export" else [])
        r = suscosim(command, *args, timeout=120)
        assert r.returncode in (0, 2), r.stdout + r.stderr
        assert "internal error" not in r.stderr and "Traceback" not in r.stderr, r.stderr
        if r.returncode == 2:
            assert name in r.stderr or "scenario key" in r.stderr, r.stderr

    run()
