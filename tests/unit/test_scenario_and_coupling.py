import numpy as np
import pytest

from cosim import scenario as sc
from cosim.errors import InputFileError, ScenarioError
from nodes.plant.coupling import StepInputs, substep_forces


def test_defaults_and_overrides(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text('[run]\nt_end = 1.0\n[controller]\nlaw = "passive"\n')
    s = sc.load(p, ["run.h=0.002", 'controller.law="tss1"', "road.type=step"])
    assert s["run"]["h"] == 0.002 and s["run"]["exchange"] == "sequential"
    assert s["controller"]["law"] == "tss1" and s["road"]["type"] == "step"


@pytest.mark.parametrize("text, key", [
    ("[run]\nh = -1\n", "run.h"),
    ('[run]\nexchange = "zigzag"\n', "run.exchange"),
    ("[run]\nbogus = 1\n", "run.bogus"),
    ('[run]\nh = "fast"\n', "run.h"),
    ("[wheels]\nx = 1\n", "wheels"),
])
def test_bad_values_name_the_key(tmp_path, text, key):
    p = tmp_path / "s.toml"
    p.write_text(text)
    with pytest.raises(ScenarioError) as exc:
        sc.load(p)
    assert exc.value.key == key and key in str(exc.value)


def test_bad_toml_names_the_file(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text("[run\n")
    with pytest.raises(InputFileError, match="s.toml"):
        sc.load(p)


def _inputs(F_t=1000.0, F_d=100.0):
    return StepInputs(F_t=np.array([F_t]), F_d=np.array([F_d]), k_t=np.array([2e5]),
                      c_eff=np.array([1500.0]), z_w=np.array([0.0]), v_rel=np.array([0.1]))


def test_coupling_modes():
    now, before = _inputs(), _inputs(F_t=900.0, F_d=80.0)
    st = {"z_w": np.array([0.001]), "v_w": np.array([0.2]), "v_b": np.array([0.0])}
    assert substep_forces("hold", now, before, 5e-4, 1e-3, st)[0][0] == 1000.0
    F_t, F_d = substep_forces("linear", now, before, 5e-4, 1e-3, st)
    assert F_t[0] == pytest.approx(1050.0) and F_d[0] == pytest.approx(110.0)
    F_t, F_d = substep_forces("jacobian", now, before, 5e-4, 1e-3, st)
    assert F_t[0] == pytest.approx(1000.0 - 2e5 * 0.001)
    assert F_d[0] == pytest.approx(100.0 + 1500.0 * 0.1)
    # lift-off within the step: the tyre cannot pull
    F_t, _ = substep_forces("jacobian", now, None, 5e-4, 1e-3, dict(st, z_w=np.array([0.01])))
    assert F_t[0] == 0.0


def test_relative_paths_resolve_against_scenario_folder_and_cwd(tmp_path, monkeypatch):
    from cosim import scenario as sc

    sub = tmp_path / "study"
    sub.mkdir()
    (sub / "s.toml").write_text(
        '[road]\ntype = "csv"\npath = "data/road.csv"\nspeed_kmh = 30.0\n'
        '[fatigue]\ninfluence = "builtin"\n')
    monkeypatch.chdir(tmp_path)
    s = sc.load(sub / "s.toml")
    assert s["road"]["path"] == str(sub.resolve() / "data" / "road.csv")
    assert s["fatigue"]["influence"] == "builtin"
    s = sc.load(sub / "s.toml", ['road.path="other.csv"'])
    assert s["road"]["path"] == str(tmp_path / "other.csv")
