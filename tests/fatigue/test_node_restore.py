"""The fatigue node's checkpoint restore (#43, #42): a state that fits continues with the same
bits; plain data of the wrong shape is a CheckpointError (exit 2) naming the node and the
checkpoint, never an internal error in the step loop."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cosim import plaindata
from cosim.checkpoint import CheckpointError
from cosim.errors import RunError
from cosim.load_blocks import StepBlocks
from cosim.run_checkpoint import NodeCheckpoints
from nodes.fatigue.config import FatigueConfig
from nodes.fatigue.live_sink import Track
from nodes.fatigue.node import restore
from nodes.fatigue.synthetic import pave_like_loads
from nodes.fatigue.worker import LiveFatigue
from tests.conftest import COARSE_ARM

CFG = FatigueConfig.from_dict({"influence": str(COARSE_ARM), "block_samples": 200})
FIELDS = ("damage", "eq_max", "eq_min", "eq_range_max", "n_cycles")


@pytest.fixture(autouse=True)
def _cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("SUSCOSIM_CACHE", str(tmp_path_factory.getbasetemp() / "cache"))


def _plan(start_k: int) -> NodeCheckpoints:
    return NodeCheckpoints("fatigue", Path("/tmp/run"), 0.002, frozenset(), start_k,
                           Path("/tmp/run/checkpoints/k000600"))


def _track() -> Track:
    return Track(None, CFG, "arm", [])


def test_a_state_that_fits_continues_with_the_same_bits() -> None:
    t, loads = pave_like_loads(1.2, seed=3, static_n=6000, rms_n=4000)
    names = list(loads)
    arr = np.stack([loads[c] for c in names], axis=1)
    live = LiveFatigue(CFG, names, 40.0, total_samples=t.size)
    live.update(t[:400], arr[:400])
    state = {"live": live, "steps": StepBlocks(200), "next_k": 400, "t_last": float(t[399])}
    tr = _track()
    restore(tr, plaindata.decode(plaindata.encode(state)), _plan(400))  # as a file holds it
    assert tr.next_k == 400 and tr.t_last == float(t[399]) and tr.live is not live
    assert tr.live is not None
    for lf in (live, tr.live):
        lf.update(t[400:], arr[400:])
    a, b = live.result(), tr.live.result()
    for f in FIELDS:
        assert np.array_equal(getattr(a, f), getattr(b, f), equal_nan=True)
    with pytest.raises(RunError, match="resumes at 200"):  # a checkpoint of another step
        restore(_track(), state, _plan(200))


@pytest.mark.parametrize("state,named", [
    ({"live": None, "steps": StepBlocks(200), "next_k": 0, "t_last": 0.0}, "'live' is a NoneType"),
    ({"live": {"damage": [1.0]}, "steps": None, "next_k": 0, "t_last": 0.0}, "'live' is a dict"),
    ({"steps": StepBlocks(200), "next_k": 0, "t_last": 0.0}, "KeyError: 'live'"),
    ({"live": "x", "steps": "y", "next_k": 0}, "TypeError"),
])
def test_plain_data_that_does_not_fit_is_a_checkpoint_error_naming_node_and_file(state, named
                                                                                 ) -> None:
    tr = _track()
    with pytest.raises(CheckpointError) as err:
        restore(tr, plaindata.decode(plaindata.encode(state)), _plan(0))
    msg = str(err.value)
    assert msg.startswith("fatigue: ") and "checkpoints/k000600" in msg and named in msg
    assert err.value.exit_code == 2
    assert tr.live is None and tr.next_k == 0  # nothing half put in


def test_fields_of_the_wrong_type_around_a_fitting_engine() -> None:
    _, loads = pave_like_loads(0.1, seed=3, static_n=6000, rms_n=4000)
    live = LiveFatigue(CFG, list(loads), 40.0)
    for bad, named in (({"next_k": "x"}, "ValueError"), ({"t_last": None}, "TypeError"),
                       ({"next_k": [3]}, "TypeError")):
        state = {"live": live, "steps": StepBlocks(200), "next_k": 0, "t_last": 0.0, **bad}
        with pytest.raises(CheckpointError, match=f"fatigue: .*{named}"):
            restore(_track(), state, _plan(0))
