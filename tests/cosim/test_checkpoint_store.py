"""cosim.checkpoint: atomic node files, the manifest written last, resume refusals (#29 item 4)."""

from __future__ import annotations

import random
from pathlib import Path

import numpy as np
import pytest

from cosim import checkpoint as ck

SCEN = {"run": {"h": 0.001, "checkpoint_every_s": 0.5}, "road": {"length_m": 20.0}}


def _save(run: Path, k: int, t: float, scen: dict = SCEN) -> dict:
    rng = random.Random(7)
    rng.random()
    states = {
        "plant": {"q": np.arange(6, dtype=float) * 0.1, "t": t},
        "road": {"x_m": 12.5, "rng": rng.getstate(),
                 "np_rng": np.random.default_rng(3).bit_generator.state},
        "fatigue": {"residues": [np.array([1.0, -2.0, 3.5])], "damage": np.array([1e-9, 2e-9])},
    }
    entries = {n: ck.write_node_state(run, k, n, s) for n, s in states.items()}
    ck.write_manifest(run, k, t, scen, entries)
    return states


def test_roundtrip_is_exact_and_last_complete_is_chosen(tmp_path: Path) -> None:
    _save(tmp_path, 500, 0.5)
    states = _save(tmp_path, 1000, 1.0)
    # an incomplete checkpoint (node files, no manifest: killed before the orchestrator wrote it)
    ck.write_node_state(tmp_path, 1500, "plant", {"q": 1})
    got = ck.load_for_resume(tmp_path, SCEN)
    assert (got.k, got.t) == (1000, 1.0)
    road = ck.read_node_state(got, "road")
    r = random.Random()
    r.setstate(road["rng"])
    r2 = random.Random(7)
    r2.random()
    assert r.random() == r2.random()
    fat = ck.read_node_state(got, "fatigue")
    assert np.array_equal(fat["damage"], states["fatigue"]["damage"])
    assert ck.read_node_state(got, "plant")["q"].tobytes() == states["plant"]["q"].tobytes()
    assert not list(tmp_path.rglob("*.tmp"))
    assert ck.load_for_resume(tmp_path, SCEN, at_t=0.5).k == 500


def test_refuses_no_complete_checkpoint(tmp_path: Path) -> None:
    ck.write_node_state(tmp_path, 10, "plant", {"q": 1})
    with pytest.raises(ck.CheckpointError, match="no complete checkpoint") as e:
        ck.load_for_resume(tmp_path, SCEN)
    assert e.value.exit_code == 2


def test_refuses_changed_scenario(tmp_path: Path) -> None:
    _save(tmp_path, 500, 0.5)
    other = {**SCEN, "road": {"length_m": 30.0}}
    with pytest.raises(ck.CheckpointError, match="scenario differs"):
        ck.load_for_resume(tmp_path, other)


@pytest.mark.parametrize("damage", ["flip", "truncate", "delete"])
def test_refuses_damaged_node_file(tmp_path: Path, damage: str) -> None:
    _save(tmp_path, 500, 0.5)
    f = ck.step_folder(tmp_path, 500) / "road.ckpt"
    data = bytearray(f.read_bytes())
    if damage == "flip":
        data[-3] ^= 0x01
        f.write_bytes(bytes(data))
    elif damage == "truncate":
        f.write_bytes(bytes(data[:20]))
    else:
        f.unlink()
    with pytest.raises(ck.CheckpointError, match="road"):
        ck.load_for_resume(tmp_path, SCEN)


def test_manifest_refused_when_a_node_file_is_missing(tmp_path: Path) -> None:
    e = ck.write_node_state(tmp_path, 5, "plant", {"q": 1})
    with pytest.raises(ck.CheckpointError, match="controller"):
        ck.write_manifest(tmp_path, 5, 0.005, SCEN,
                          {"plant": e, "controller": {"file": "controller.ckpt"}})
    assert not (ck.step_folder(tmp_path, 5) / ck.MANIFEST).exists()


def test_fork_time_must_exist(tmp_path: Path) -> None:
    _save(tmp_path, 500, 0.5)
    with pytest.raises(ck.CheckpointError, match="no checkpoint at t=0.7"):
        ck.load_for_resume(tmp_path, SCEN, at_t=0.7)


def test_checkpoint_schedule_and_fork_spec() -> None:
    assert ck.checkpoint_steps(0.5, 0.001, 2000) == [500, 1000, 1500]
    assert ck.checkpoint_steps(0.5, 0.001, 1500) == [500, 1000]
    with pytest.raises(ValueError, match="whole number of steps"):
        ck.checkpoint_steps(0.0015, 0.001, 100)
    with pytest.raises(ValueError, match="positive"):
        ck.checkpoint_steps(0.0, 0.001, 100)
    assert ck.parse_fork("runs/a@b@1.25") == (Path("runs/a@b"), 1.25)
    for bad in ("runs/a", "@1", "runs/a@x", "runs/a@-1"):
        with pytest.raises(ValueError, match="--fork"):
            ck.parse_fork(bad)
