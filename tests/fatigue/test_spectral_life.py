"""`suscosim fatigue RUN --method dirlik|tovo_benasciutti` (nodes/fatigue/spectral_life.py,
#44 item 2) on a run folder with imported influence tables (6 nodes, uniaxial: the
equivalent stress is the superposed sigma_x itself, so the test can build each node's history
by hand), and `[fatigue] method = "dirlik"` in a scenario (no live node; after the run)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import welch

from cosim.errors import ScenarioError
from nodes.fatigue.config import FatigueConfig
from nodes.fatigue.lib import spectral
from nodes.fatigue.lib.damage import cycle_reversals
from nodes.fatigue.node import preflight
from orchestrator.fatigue_cli import main

FS, N = 1000.0, 20000
C_BJ = np.array([3.0e4, 4.5e4, 1.0e4, 5.0e4, 2.0e4, 4.0e4])  # Pa/N: sigma_x per N of each case
C_TB = np.array([-2.0e4, 1.0e4, 3.0e4, -1.0e4, 0.5e4, 2.5e4])


def _noise(rng, lo: float, hi: float) -> np.ndarray:
    """Unit-variance Gaussian noise band-limited to [lo, hi] Hz (random phases)."""
    fr = np.fft.rfftfreq(N, 1 / FS)
    amp = np.where((fr >= lo) & (fr <= hi), 1.0, 0.0)
    x = np.fft.irfft(amp * np.exp(2j * np.pi * rng.random(fr.size)), N)
    return x / x.std()


@pytest.fixture()
def run_dir(tmp_path: Path) -> Path:
    rng = np.random.default_rng(44)
    inf = tmp_path / "inf"
    inf.mkdir()
    for name, c in (("bj_z.csv", C_BJ), ("tb_mx.csv", C_TB)):
        rows = ["node,x,y,z,Sx,Sy,Sz,Sxy,Syz,Szx"]
        rows += [f"{i + 1},{0.01 * i},0.1,0.0,{v:.6g},0,0,0,0,0" for i, v in enumerate(c)]
        (inf / name).write_text("\n".join(rows) + "\n")
    d = tmp_path / "run"
    d.mkdir()
    t = np.arange(N) / FS
    cols = {"plant/arm/ball_joint_z": 5000 + 2000 * _noise(rng, 1.0, 15.0),
            "plant/arm/torsion_bar_mx": -1500 + 800 * _noise(rng, 8.0, 40.0)}
    with open(d / "table.csv", "w") as fh:
        fh.write("t," + ",".join(cols) + "\n")
        for i in range(N):
            fh.write(",".join([repr(float(t[i]))] + [repr(float(v[i])) for v in cols.values()])
                     + "\n")
    fat = {"influence": str(inf), "mapping": {"plant/arm/ball_joint_z": "bj_z.csv",
                                              "plant/arm/torsion_bar_mx": "tb_mx.csv"}}
    (d / "scenario.json").write_text(json.dumps({"road": {"length_m": 200.0}, "fatigue": fat}))
    return d


@pytest.mark.parametrize("method", ["dirlik", "tovo_benasciutti"])
def test_the_spectral_life_of_a_run(run_dir: Path, tmp_path: Path, method: str) -> None:
    out = tmp_path / method
    assert main([str(run_dir), "--quiet", "--method", method, "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["config"]["method"] == method and s["spectral"]["method"] == method
    assert s["spectral"]["welch"]["nperseg"] == 1024
    assert s["spectral"]["welch"]["fs_hz"] == pytest.approx(FS, rel=1e-9)
    # each node by hand: sigma_x(t), its Welch PSD, the method's damage with the config's curve
    cols = np.genfromtxt(run_dir / "table.csv", delimiter=",", names=True)
    x = np.outer(C_BJ, cols["plantarmball_joint_z"]) + np.outer(C_TB,
                                                                cols["plantarmtorsion_bar_mx"])
    f, G = welch(x, fs=FS, window="hann", nperseg=1024, noverlap=512, axis=-1)
    cfg = FatigueConfig.from_dict(json.loads((run_dir / "scenario.json").read_text())["fatigue"])

    def rev(s1, s2):
        return cycle_reversals(s1, s2, cfg.material, "stress_life", cfg.mean_stress_rule,
                               cfg.endurance)
    want = spectral.damage_rate(method, spectral.moments(f, G), x.mean(axis=1), rev) * N / FS
    rows = np.genfromtxt(out / "damage_per_node.csv", delimiter=",", names=True)
    assert rows["node_id"].tolist() == [1, 2, 3, 4, 5, 6]
    np.testing.assert_allclose(rows["damage_per_pass"], want, rtol=1e-5)
    assert 0 < s["min_life_km"] == pytest.approx(0.2 / want.max(), rel=1e-5)
    assert s["critical_node_id"] == int(np.argmax(want)) + 1
    # the same run by rainflow: the lives within 3x, the same critical node
    rain = tmp_path / "rain"
    assert main([str(run_dir), "--quiet", "--out", str(rain)]) == 0
    r = json.loads((rain / "summary.json").read_text())
    assert 1 / 3 < s["min_life_km"] / r["min_life_km"] < 3
    assert r["critical_node_id"] == s["critical_node_id"]


def test_a_scenario_with_a_spectral_method_has_no_live_node() -> None:
    sc = {"run": {"mode": "distributed"}, "fatigue": {"method": "dirlik"}}
    assert preflight(sc, ["arm"]) is False
    sc["fatigue"]["live"] = True
    with pytest.raises(ScenarioError, match="after the run"):
        preflight(sc, ["arm"])


def test_findley_is_refused(run_dir: Path, tmp_path: Path, capsys) -> None:
    assert main([str(run_dir), "--quiet", "--method", "dirlik", "--equivalent", "findley",
                 "--out", str(tmp_path / "x")]) == 2
    assert "fatigue.equivalent" in capsys.readouterr().err


def test_uneven_time_steps_are_refused(run_dir: Path, tmp_path: Path, capsys) -> None:
    lines = (run_dir / "table.csv").read_text().splitlines()
    head, rest = lines[0], lines[1:]
    rest[5] = "0.00512" + rest[5][rest[5].index(","):]
    (run_dir / "table.csv").write_text("\n".join([head, *rest]) + "\n")
    assert main([str(run_dir), "--quiet", "--method", "dirlik", "--out",
                 str(tmp_path / "x")]) == 2
    assert "constant time step" in capsys.readouterr().err
