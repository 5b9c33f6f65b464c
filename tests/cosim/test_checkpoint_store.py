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


def test_plain_data_round_trips_and_refuses_what_is_not_data() -> None:
    """cosim.plaindata (#43): numbers, arrays, tuples, sets, big ints, generators and
    whitelisted classes round-trip exactly; an object array, a class outside the whitelist, a
    name that would need an import, or a dunder field is refused, in both directions."""
    import msgpack

    from cosim import plaindata as pd
    from nodes.tyre_road.wheel_paths import RoadPath

    rng = np.random.default_rng(5)
    state = {"a": np.arange(6, dtype="<i4").reshape(2, 3), "f": np.float32(1.5),
             "t": (1, "x", None), "s": frozenset({1, 2}), "big": -(2**80), "rng": rng,
             "path": RoadPath((1.0, 2.0), 10.0), 3: b"\0"}
    back = pd.decode(pd.encode(state))
    assert back["a"].dtype == np.dtype("<i4") and back["a"].tobytes() == state["a"].tobytes()
    assert type(back["f"]) is np.float32 and back["t"] == (1, "x", None)
    assert back["s"] == frozenset({1, 2}) and back["big"] == -(2**80) and back[3] == b"\0"
    assert back["rng"].random() == rng.random()
    assert type(back["path"]) is RoadPath and vars(back["path"]).keys() == \
        vars(state["path"]).keys()
    for bad in (np.array([object()]), object(), {"x": lambda: 0}, np.array(["s"])):
        with pytest.raises(pd.PlainDataError):
            pd.encode(bad)

    def obj(name: str, fields: dict) -> bytes:
        inner = msgpack.packb([name, fields], use_bin_type=True)
        return msgpack.packb(msgpack.ExtType(7, inner), use_bin_type=True)

    for name, fields in (("os.system", {}), ("subprocess.Popen", {"args": "id"}),
                         ("nodes.tyre_road.wheel_paths.RoadPath", {"__class__": 1})):
        with pytest.raises(pd.PlainDataError):
            pd.decode(obj(name, fields))
    arr = msgpack.packb(msgpack.ExtType(1, msgpack.packb(["|O", [1], b"\0" * 8])))
    with pytest.raises(pd.PlainDataError, match="not a number type"):
        pd.decode(arr)
