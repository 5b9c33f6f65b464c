"""#47: one fatigue answer per setting. The headline life of ``suscosim fatigue`` is its S-N
method's own ``sn_methods`` entry at the scenario's reliability (FKM with FKM's Haigh
diagram, whatever ``mean_stress`` says), life = track length / largest damage per pass, the
critical node is the most damaged row of ``damage_per_node.csv`` and the printed lines say
what the summary says; FKM's temperature factor K_T,D; no path of this machine in shipped
data or in a run's summary.

The property test draws settings the CLI accepts on a short synthetic history (200 samples,
the coarse test arm: on it, as on the CAD arm, some cycles pass Shigley's knee and none FKM's
at the default settings), runs the CLI in this process and checks each; the critical node's
damage is recomputed outside the engine (superposition, equivalent stress, whole-history
rainflow, Miner with the rule the method must use)."""

from __future__ import annotations

import contextlib
import csv
import hashlib
import io
import itertools
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from nodes.fatigue.config import BUILTIN_PART, RESIDUES, SN_METHODS, FatigueConfig
from nodes.fatigue.lib.counting import count_series
from nodes.fatigue.lib.damage import cycle_damage
from nodes.fatigue.lib.equivalent_stress import equivalent
from nodes.fatigue.lib.fkm import temperature_factor
from nodes.fatigue.lib.influence_set import short_channel
from nodes.fatigue.lib.life_models import ENDURANCE_MODES
from nodes.fatigue.lib.mean_stress import MEAN_STRESS_METHODS
from nodes.fatigue.lib.superposition import stress_history
from nodes.fatigue.worker import load_influence
from orchestrator.fatigue_cli import main
from tests.conftest import COARSE_ARM

REPO = Path(__file__).resolve().parents[2]
TRACK_M = 4.0
_OUT = itertools.count()


def _history() -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """200 samples of the arm's main joint loads (N, N m): preloads and three sines, so that
    cycles of several sizes and means reach both S-N curves' knees."""
    t = np.arange(200) * 1e-3
    w = np.sin(60 * t) + 0.5 * np.sin(190 * t) + 0.3 * np.sin(410 * t + 1.0)
    return t, {"plant/arm/ball_joint_z": 5400 + 4200 * w,
               "plant/arm/torsion_bar_mx": -1580 - 900 * w,
               "plant/arm/bush_front_z": -2700 - 2000 * w,
               "plant/arm/bush_rear_z": -2700 - 2100 * w}


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("h47") / "run"
    d.mkdir()
    t, cols = _history()
    with open(d / "table.csv", "w") as fh:
        fh.write("t," + ",".join(cols) + "\n")
        for i in range(t.size):
            fh.write(",".join([repr(float(t[i]))] + [repr(float(v[i])) for v in cols.values()])
                     + "\n")
    (d / "scenario.json").write_text(json.dumps({"road": {"length_m": TRACK_M},
                                                 "fatigue": {"influence": str(COARSE_ARM)}}))
    return d


def _cli(run: Path, sets: dict) -> tuple[int, str, Path]:
    out = run.parent / f"out{next(_OUT)}"
    args = [str(run), "--quiet", "--out", str(out)]
    for k, v in sets.items():
        args += ["--set", f"{k}={json.dumps(v)}"]
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(io.StringIO()):
        code = main(args)
    return code, buf.getvalue(), out


def _km(v: float | str) -> float:
    return math.inf if v == "inf" else float(v)


def _node_damage(sets: dict, node_id: int, rule: str) -> float:
    """The damage per pass of one node, outside the engine: its stresses by superposition of
    the loads, the equivalent stress, the whole history rainflow-counted, Miner with the
    method's curve and the mean-stress rule ``rule`` given here, not taken from the config."""
    section: dict = {"influence": str(COARSE_ARM)}  # the run's
    for k, v in sets.items():
        *head, last = k.split(".")
        node = section
        for h in head:
            node = node.setdefault(h, {})
        node[last] = v
    cfg = FatigueConfig.from_dict(section)
    inf = load_influence(cfg)
    c = int(np.flatnonzero(inf.node_ids == node_id)[0])
    t, loads = _history()
    by_case = {short_channel(k): v for k, v in loads.items()}
    F = np.column_stack([by_case.get(n, np.zeros(t.size)) for n in inf.case_names])
    eq = equivalent(stress_history(F, inf.coefficients[:, c:c + 1, :]), cfg.equivalent)[:, 0]
    cyc = count_series(eq, cfg.residue)
    return float(np.sum(cycle_damage(cyc, cfg.material, cfg.method, rule, cfg.endurance)))


PROB = st.one_of(st.sampled_from([0.5, 0.9, 0.975, 0.99]),
                 st.floats(0.5, 0.999999, allow_nan=False))
SETTINGS = st.fixed_dictionaries({
    "component.method": st.sampled_from(SN_METHODS),
    "component.reliability": PROB,
    "component.survival_probability": PROB,
    "mean_stress": st.sampled_from(MEAN_STRESS_METHODS),
    "equivalent": st.sampled_from(("abs_max_principal", "signed_von_mises")),
    "residue": st.sampled_from(RESIDUES),
    "endurance": st.sampled_from(ENDURANCE_MODES),
    "method": st.sampled_from(("stress_life", "strain_life")),  # the rainflow methods
})


@settings(max_examples=15, deadline=None, derandomize=True, database=None,
          phases=(Phase.explicit, Phase.generate),  # no shrinking: a failure prints its draw
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(sets=SETTINGS)
def test_the_headline_is_its_methods_entry(run: Path, sets: dict) -> None:
    code, printed, out = _cli(run, sets)
    assert code == 0, printed
    s = json.loads((out / "summary.json").read_text())
    m, P = sets["component.method"], sets["component.reliability"]
    rule = "fkm" if m == "fkm" else sets["mean_stress"]
    # the headline is its method's entry at the scenario's reliability, by that rule
    entry = s["sn_methods"]["methods"][m][repr(P)]
    assert s["min_life_km"] == entry["life_km"]
    assert s["max_damage_per_pass"] == entry["max_damage_per_pass"]
    assert s["critical_node_id"] == entry["critical_node_id"]
    assert entry["mean_stress"] == rule == s["config"]["mean_stress_applied"]
    assert s["sn_methods"]["methods"]["fkm"][repr(P)]["mean_stress"] == "fkm"
    # life = track length / largest damage per pass
    D = _km(s["max_damage_per_pass"])
    life = _km(s["min_life_km"])
    assert life == (math.inf if D == 0 else pytest.approx(TRACK_M / 1000 / D, rel=1e-12))
    # the critical node is the most damaged row of damage_per_node.csv
    with open(out / "damage_per_node.csv", newline="") as fh:
        rows = [(int(r["node_id"]), float(r["damage_per_pass"])) for r in csv.DictReader(fh)]
    ids = np.array([r[0] for r in rows])
    dmg = np.array([r[1] for r in rows])
    assert dmg[ids == s["critical_node_id"]][0] == dmg.max()
    assert dmg.max() == pytest.approx(D, rel=1e-6)
    # the same damage outside the engine, with the rule the method must use
    assert _node_damage(sets, s["critical_node_id"], rule) == pytest.approx(D, rel=1e-9)
    # the printed lines are the summary's
    head = re.search(r"min life (\S+) km .*\(S-N (\w+) at P = (\S+), mean stress (\w+)\)",
                     printed)
    assert head, printed
    assert head.groups() == (f"{life:.4g}", m, repr(P), rule)
    assert f"S-N {m} (mean stress {rule}): " in printed
    assert f"{_km(entry['life_km']):.4g} km at P = {repr(P)}" in printed
    assert f"critical node {s['critical_node_id']} " in printed
    assert f"max damage/pass {D:.3e}" in printed


def test_fkm_at_150_c_is_the_20_c_life_times_k_td_to_the_k(run: Path) -> None:
    # K_T,D = 1 - 1.4e-3 (150 - 100) = 0.93 scales sigma_WK; with the line continued below
    # the knee (endurance "none") every cycle's N scales by K_T,D^k: the life by 0.93^5
    assert temperature_factor(150.0) == pytest.approx(0.93, rel=1e-15)
    assert temperature_factor(20.0) == temperature_factor(100.0) == 1.0
    base = {"component.method": "fkm", "endurance": "none"}
    lives = {}
    for T in (20.0, 150.0):
        code, _, out = _cli(run, {**base, "component.temperature_c": T})
        assert code == 0
        s = json.loads((out / "summary.json").read_text())
        f = s["config"]["fatigue_properties"]["sn_curve"]["factors"]
        assert f["K_T_D"] == temperature_factor(T)
        lives[T] = s["min_life_km"]
    assert lives[150.0] / lives[20.0] == pytest.approx(0.93 ** 5, rel=1e-9)


def test_a_temperature_fkm_does_not_cover_is_refused(run: Path) -> None:
    code, _, _ = _cli(run, {"component.method": "fkm", "component.temperature_c": 520})
    assert code == 2
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        assert main([str(run), "--quiet", "--out", str(run.parent / "refused"),
                     "--set", "component.method=fkm",
                     "--set", "component.temperature_c=-50"]) == 2
    assert "fatigue.component.temperature_c" in err.getvalue()
    assert "-40 to 500" in err.getvalue()
    # Shigley covers 520 °C (kd): its run stands, the FKM comparison is left out, saying why
    code, printed, out = _cli(run, {"component.temperature_c": 520})
    assert code == 0
    sm = json.loads((out / "summary.json").read_text())["sn_methods"]
    assert list(sm["methods"]) == ["shigley"] and "500" in sm["left_out"]["fkm"]
    assert "S-N fkm: not computed (temperature_c = 520 °C" in printed


def _machine_paths(tmp: Path) -> list[str]:
    return [str(REPO), str(Path.home()) + "/", "/root/", "/tmp/", str(tmp)]


def test_no_path_of_this_machine_in_shipped_data_or_a_summary(run: Path) -> None:
    bad = _machine_paths(run.parent)
    shipped = [p for p in (REPO / "nodes").rglob("*")
               if p.is_file() and "__pycache__" not in p.parts and p.suffix != ".pyc"]
    assert any(p.suffix == ".npz" for p in shipped)
    for p in shipped:
        if p.suffix == ".npz":
            with np.load(p, allow_pickle=False) as z:
                text = " ".join(str(z[k]) for k in z.files if z[k].dtype.kind == "U")
        else:
            text = p.read_bytes().decode("utf-8", "replace")
        hits = [b for b in (bad if p.suffix != ".py" else [str(REPO)]) if b in text]
        assert not hits, f"{p.relative_to(REPO)} names {hits}"
    # the shipped results name their part file relative to themselves, with its hash
    with np.load(BUILTIN_PART.with_name("lower_arm.influence.npz")) as z:
        meta = json.loads(str(z["meta"]))
    assert meta["part"] == "lower_arm.toml"
    assert meta["part_sha256"] == hashlib.sha256(BUILTIN_PART.read_bytes()).hexdigest()
    # a run's summary: the same names, no path
    code, _, out = _cli(run, {"component.method": "fkm", "influence": "builtin"})
    assert code == 0
    text = (out / "summary.json").read_text()
    assert not [b for b in bad if b in text], text
    inf = json.loads(text)["influence"]
    assert (inf["part"], inf["part_sha256"]) == (meta["part"], meta["part_sha256"])
