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


def _ch3_with(fmu: Path, out: Path, *more: str):
    from ..conftest import suscosim

    return suscosim("run", str(ROOT / "scenarios" / "ch3_step_quarter_car.toml"), "--mode",
                    "distributed", "--quiet", "--out", str(out), "--set", "run.t_end=1.0",
                    "--set", f'controller={{law="fmu", fmu="{fmu}"}}', *more)


def test_a_run_with_a_stateful_fmu_resumes_bit_for_bit(stateful_fmu, tmp_path):
    """Through the node shell: the FMU's state saved at 0.5 s, a resume from there (the
    controller puts it back at its first step, which starts the FMU) ends with the
    uninterrupted run's table, byte for byte."""
    import shutil

    from ..conftest import suscosim

    r = _ch3_with(stateful_fmu, tmp_path / "a", "--set", "run.checkpoint_every_s=0.5")
    assert r.returncode == 0, r.stderr
    shutil.copytree(tmp_path / "a", tmp_path / "b")
    (tmp_path / "b" / "table.parquet").unlink()
    r = suscosim("run", "--resume", str(tmp_path / "b"), "--quiet")
    assert r.returncode == 0 and "step 500" in r.stdout, r.stdout + r.stderr
    assert (tmp_path / "a" / "table.parquet").read_bytes() == \
        (tmp_path / "b" / "table.parquet").read_bytes()


def test_a_run_that_cannot_checkpoint_its_fmu_is_refused_before_it_steps(tmp_path):
    path = tmp_path / "tss1.fmu"
    export_fmu(sc.load(ROOT / "scenarios" / "ch5_qvm_tss1_random.toml"), path, fmi=2)
    r = _ch3_with(path, tmp_path / "run", "--set", "run.checkpoint_every_s=0.5")
    assert r.returncode == 2, r.stdout + r.stderr
    assert "tss1.fmu cannot be checkpointed" in r.stderr and "Traceback" not in r.stderr
    assert not list((tmp_path / "run").glob("checkpoints/*/manifest.json"))
