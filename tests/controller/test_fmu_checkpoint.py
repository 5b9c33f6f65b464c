"""FMU controllers in checkpoints (#29 item 6), on real FMUs run by FMPy: one that declares
canGetAndSetFMUstate + canSerializeFMUstate continues bit for bit from its serialised state in
a fresh instance; one that does not (the project's export-fmu FMUs) is refused, exit 2, named."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pythonfmu import FmuBuilder

from cosim import scenario as sc
from cosim.checkpoint import CheckpointError
from nodes.controller.laws import build_controller
from orchestrator.export_fmu import export_fmu

from ..conftest import ROOT

H, N = 0.002, 2


def states(steps: int, seed: int):
    rng = np.random.default_rng(seed)
    for _ in range(steps):
        yield {"z_b": rng.normal(0, .01, N), "v_b": rng.normal(0, .3, N),
               "z_w": rng.normal(0, .01, N), "v_w": rng.normal(0, .6, N)}


@pytest.fixture(scope="module")
def stateful_fmu(tmp_path_factory) -> Path:
    dest = tmp_path_factory.mktemp("fmu_state")
    return Path(FmuBuilder.build_FMU(Path(__file__).parent / "data" / "filtered_skyhook_slave.py",
                                     dest=dest, canGetAndSetFMUstate="true",
                                     canSerializeFMUstate="true"))


def test_fmu_state_restored_in_a_fresh_instance_continues_bit_for_bit(stateful_fmu):
    cfg = {"law": "fmu", "fmu": str(stateful_fmu)}
    parent = build_controller(cfg, N, H)
    child = build_controller(cfg, N, H)
    try:
        first = list(states(150, 1))
        for k, s in enumerate(first):
            parent.step(k * H, s)
        saved = parent.checkpoint_state()
        assert len(saved["states"]) == N
        after = list(states(150, 2))
        ref = [parent.step((150 + k) * H, s).F_d.copy() for k, s in enumerate(after)]
        child.restore_state(saved, 150 * H, first[-1])
        got = [child.step((150 + k) * H, s).F_d.copy() for k, s in enumerate(after)]
        assert np.abs(ref[0]).max() > 0  # the filter state carries a force
        for a, b in zip(ref, got, strict=True):
            assert a.tobytes() == b.tobytes()
        # and it is the state that matters: a fresh instance without restore differs
        fresh = build_controller(cfg, N, H)
        try:
            other = fresh.step(150 * H, after[0]).F_d
            assert other.tobytes() != ref[0].tobytes()
        finally:
            fresh.close()
    finally:
        parent.close()
        child.close()


@pytest.mark.parametrize("fmi", [2, 3])
def test_fmu_without_get_set_state_is_refused_exit_2(tmp_path, fmi):
    path = tmp_path / f"tss1_{fmi}.fmu"
    export_fmu(sc.load(ROOT / "scenarios" / "ch5_qvm_tss1_random.toml"), path, fmi=fmi)
    ctl = build_controller({"law": "fmu", "fmu": str(path)}, N, H)
    try:
        for k, s in enumerate(states(3, 1)):
            ctl.step(k * H, s)
        with pytest.raises(CheckpointError, match="canGetAndSetFMUstate") as e:
            ctl.checkpoint_state()
        assert e.value.exit_code == 2 and path.name in str(e.value)
        with pytest.raises(CheckpointError, match="cannot be checkpointed"):
            ctl.restore_state({"fmu": path.name, "states": []}, 0.0, {})
    finally:
        ctl.close()
