"""#46 item 1: every file a user names is opened by cosim.safe_open: a device or a named pipe
is refused at once (exit 2, the key named), a regular file is read within its kind's limit
counted in bytes read (not st_size)."""

from __future__ import annotations

import os
import threading
from pathlib import Path

import pytest

from cosim import safe_open
from cosim.errors import InputFileError
from tests.conftest import suscosim

SCENARIO = "scenarios/ch4_qvm_realistic_pave.toml"


@pytest.fixture()
def fifo(tmp_path: Path) -> Path:
    path = tmp_path / "pipe.csv"
    os.mkfifo(path)
    return path


def _in_thread(fn, *args):
    """``fn(*args)``'s result or exception; the thread is given 10 s (a FIFO opened for
    reading without O_NONBLOCK would block until a writer came: never)."""
    box: dict = {}

    def target() -> None:
        try:
            box["value"] = fn(*args)
        except Exception as exc:  # noqa: BLE001 - handed to the test
            box["error"] = exc

    th = threading.Thread(target=target, daemon=True)
    th.start()
    th.join(10.0)
    assert not th.is_alive(), f"{fn.__name__} blocked"
    return box


@pytest.mark.parametrize("reader", [safe_open.read_user_file, safe_open.check_user_file])
def test_a_fifo_and_a_device_are_refused_without_blocking(reader, fifo: Path) -> None:
    for path, what in ((fifo, "named pipe"), (Path("/dev/zero"), "character device")):
        box = _in_thread(reader, path, "tir", "tyre.tir")
        err = box.get("error")
        assert isinstance(err, InputFileError), box
        assert str(path) in str(err) and "tyre.tir" in str(err) and what in str(err)
    box = _in_thread(reader, fifo.parent, "tir", "tyre.tir")
    assert "a folder, not a regular file" in str(box.get("error"))


def test_the_limit_counts_bytes_read_and_the_environment_raises_it(tmp_path: Path,
                                                                  monkeypatch) -> None:
    path = tmp_path / "big.tir"
    path.write_bytes(b"x" * (safe_open.MiB + 1))
    monkeypatch.setenv("SUSCOSIM_MAX_TIR_MB", "1")
    with pytest.raises(InputFileError, match="tyre.tir: larger than the 1 MiB"):
        safe_open.read_user_file(path, "tir", "tyre.tir")
    with pytest.raises(InputFileError, match="larger than the 1 MiB"):
        safe_open.check_user_file(path, "tir", "tyre.tir")
    # the stream stops at limit + 1 bytes however the reader reads (line by line here)
    with pytest.raises(InputFileError, match="larger than"):
        with safe_open.open_user_text(path, "tir", "tyre.tir") as fh:
            for _ in fh:
                pass
    monkeypatch.setenv("SUSCOSIM_MAX_TIR_MB", "2")
    assert len(safe_open.read_user_file(path, "tir")) == safe_open.MiB + 1
    monkeypatch.setenv("SUSCOSIM_MAX_TIR_MB", "lots")
    with pytest.raises(InputFileError, match="SUSCOSIM_MAX_TIR_MB"):
        safe_open.limit("tir")


def test_a_symlink_leaving_the_handed_folder_is_refused(tmp_path: Path) -> None:
    outside = tmp_path / "secret.json"
    outside.write_text("{}")
    run = tmp_path / "run"
    run.mkdir()
    (run / "scenario.json").symlink_to(outside)
    with pytest.raises(InputFileError, match="leaves the folder"):
        safe_open.read_user_text(run / "scenario.json", "scenario", inside=run)
    (run / "ok.json").write_text("{}")
    assert safe_open.read_user_text(run / "ok.json", "scenario", inside=run) == "{}"


def _settings(key: str, path: Path) -> list[str]:
    if key == "road.path":
        return ["--set", f'road={{ type = "csv", path = "{path}", speed_kmh = 36.0 }}']
    if key == "tyre.tir":
        return ["--set", 'tyre.model="magic_formula"', "--set", f'tyre.tir="{path}"']
    if key == "fatigue.influence":
        return ["--set", f'fatigue={{ influence = "{path}", mapping = {{ ball_joint_z = '
                         f'"{path.name}" }} }}']
    return ["--set", f'{key}="{path}"']


KEYS = ("road.path", "fatigue.influence", "vehicle.corner", "tyre.tir")


@pytest.mark.parametrize("key", KEYS)
@pytest.mark.parametrize("device", ["/dev/zero", "fifo"])
def test_check_refuses_a_device_or_a_fifo_naming_the_key(key: str, device: str,
                                                          fifo: Path) -> None:
    path = fifo if device == "fifo" else Path(device)
    res = suscosim("check", SCENARIO, *_settings(key, path), timeout=60)
    assert res.returncode == 2, res.stdout + res.stderr
    last = res.stderr.strip().splitlines()[-1]
    assert str(path) in last and key in last and "not a regular file" in last, last


@pytest.mark.parametrize("key, device", zip(KEYS, ["fifo", "/dev/zero", "fifo", "/dev/zero"],
                                            strict=True))
def test_run_refuses_a_device_or_a_fifo_naming_the_key(key: str, device: str, fifo: Path,
                                                        tmp_path: Path) -> None:
    path = fifo if device == "fifo" else Path(device)
    res = suscosim("run", SCENARIO, "--mode", "monolithic", "--quiet", "--out",
                   str(tmp_path / "run"), *_settings(key, path), timeout=60)
    assert res.returncode == 2, res.stdout + res.stderr
    last = res.stderr.strip().splitlines()[-1]
    assert str(path) in last and key in last and "not a regular file" in last, last
