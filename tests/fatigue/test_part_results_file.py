"""A part's shipped results file (``PART.influence.npz``, nodes/fatigue/parts/results_file.py):
`suscosim part solve` writes it, runs take it only when it is for this very part, a damaged
or foreign file is a clear error, and the built-in arm's shipped results are its current
part file's."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from cosim.errors import InputFileError
from nodes.fatigue.config import BUILTIN_PART, FatigueConfig
from nodes.fatigue.parts.build import part_influence
from nodes.fatigue.parts.results_file import (
    current_key,
    part_results,
    read_results,
    results_path,
)
from nodes.fatigue.parts.schema import load_part
from nodes.fatigue.worker import load_influence
from orchestrator.studies.part_check import main as part_main
from tests.fatigue.test_part_user import make_link, write_part


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    """The test link, solved once with `suscosim part solve` (its results beside it)."""
    folder = tmp_path_factory.mktemp("results")
    make_link(folder)
    path = write_part(folder, mesh="size = 0.02\nfillet_size = 0.01")
    assert part_main(["solve", str(path)]) == 0
    return path


def test_solve_writes_results_that_runs_take_without_solving(solved, tmp_path, monkeypatch,
                                                             capsys):
    monkeypatch.setenv("SUSCOSIM_CACHE", str(tmp_path / "cache"))
    part = load_part(solved)
    assert results_path(part).is_file()
    key, shipped = read_results(results_path(part))
    assert key == current_key(part)
    inf = part_results(part)
    assert not (tmp_path / "cache").exists()  # nothing solved, nothing cached
    np.testing.assert_array_equal(inf.coefficients, shipped.coefficients)
    # the same numbers as a fresh solve (the results are the FE's, not a copy of something)
    fresh = part_influence(part, use_cache=False)
    np.testing.assert_array_equal(inf.coefficients, fresh.coefficients)
    np.testing.assert_array_equal(inf.node_xyz, fresh.node_xyz)
    assert inf.case_names == fresh.case_names
    # the fatigue worker's resolution of a part file goes through it too
    cfg = FatigueConfig.from_dict({"influence": str(solved)})
    np.testing.assert_array_equal(load_influence(cfg).coefficients, shipped.coefficients)


def test_results_of_another_version_are_not_used(solved, tmp_path, monkeypatch):
    monkeypatch.setenv("SUSCOSIM_CACHE", str(tmp_path / "cache"))
    folder = tmp_path / "changed"
    shutil.copytree(solved.parent, folder)
    # the same part with a finer mesh recipe: its results file no longer matches
    changed = write_part(folder, mesh="size = 0.015\nfillet_size = 0.0075")
    part = load_part(changed)
    assert read_results(results_path(part))[0] != current_key(part)
    said: list[str] = []
    inf = part_results(part, log=said.append)
    assert said and "another version" in said[0]
    _, old = read_results(results_path(part))
    assert inf.n_nodes != old.n_nodes  # solved on the new mesh, not the shipped one
    assert len(list((tmp_path / "cache" / "parts").glob("*.npz"))) == 1


def test_damaged_and_foreign_files_are_named_errors(solved, tmp_path):
    folder = tmp_path / "bad"
    shutil.copytree(solved.parent, folder)
    part = load_part(folder / solved.name)
    path = results_path(part)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])  # cut off
    with pytest.raises(InputFileError, match="unreadable part results") as err:
        part_results(part)
    assert path.name in str(err.value)
    np.savez(path.with_suffix(""), coefficients=np.zeros((1, 2, 6)))  # numpy adds .npz
    with pytest.raises(InputFileError, match="not a suscosim-part-results file"):
        part_results(part)
    path.write_bytes(data)
    _, inf = read_results(path)
    bad = inf.coefficients.copy()
    bad[0, 0, 0] = np.nan
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["coefficients"] = bad
    np.savez(path.with_suffix(""), **arrays)
    with pytest.raises(InputFileError, match="NaN"):
        part_results(part)


def test_builtin_arm_ships_results_of_its_current_part_file():
    """The default fatigue arm's results file is for the part file as committed (a change
    of the part file, its CAD parameters or the FE version without `suscosim part solve`
    fails here, not in a user's run as a silent re-solve)."""
    part = load_part(BUILTIN_PART)
    key, inf = read_results(results_path(part))
    assert key == current_key(part)
    assert inf.case_names == part.channels
    assert inf.meta["mass_kg"] == pytest.approx(5.0, rel=0.10)  # issue #26 item 2's bar
    assert inf.meta["natural_frequencies_hz"][0] >= 300.0


def test_part_check_takes_the_static_loads_of_the_upper_arm_channel_too() -> None:
    from orchestrator.studies.part_check import _static_loads

    lower = _static_loads(["ball_joint_z", "bush_front_x"])
    upper = _static_loads(["upper_ball_joint_y", "upper_bush_front_y"])
    assert set(lower) == {"ball_joint_z", "bush_front_x"}
    assert set(upper) == {"upper_ball_joint_y", "upper_bush_front_y"}
    assert abs(upper["upper_ball_joint_y"]) > 100.0  # the upper ball joint carries load
