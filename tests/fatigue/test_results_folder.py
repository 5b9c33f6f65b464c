"""#30 items 2, 3: a results folder is written aside and renamed into place (never a new
summary beside an old map); a part that fails on the first cycle is a result (life 0 km,
exit 0); a what-if goes to fatigue-<hash>/ (or --out) and the live fatigue/ stays."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from nodes.fatigue.run_dir import settings_hash
from orchestrator.fatigue_cli import main


def strict(text: str) -> dict:
    def refuse(x: str) -> None:
        raise AssertionError(f"non-strict JSON constant {x}")

    return json.loads(text, parse_constant=refuse)


@pytest.fixture()
def run_dir(tmp_path: Path) -> Path:
    d = tmp_path / "run"
    d.mkdir()
    t = np.arange(0.0, 0.4, 1e-3)
    cols = {"plant/arm/ball_joint_z": 5400 + 2500 * np.sin(50 * t),
            "plant/arm/torsion_bar_mx": -1580 - 600 * np.sin(50 * t),
            "plant/arm/bush_front_z": -2700 - 1200 * np.sin(50 * t),
            "plant/arm/bush_rear_z": -2700 - 1300 * np.sin(50 * t)}
    with open(d / "table.csv", "w") as fh:
        fh.write("t," + ",".join(cols) + "\n")
        for i in range(t.size):
            fh.write(",".join([repr(float(t[i]))] + [repr(float(v[i])) for v in cols.values()])
                     + "\n")
    (d / "scenario.json").write_text(json.dumps({"road": {"length_m": 4.0}, "fatigue": {}}))
    return d


def test_first_cycle_failure_is_life_zero_and_whatif_keeps_live_results(run_dir: Path,
                                                                        capsys) -> None:
    assert main([str(run_dir), "--quiet"]) == 0
    live = run_dir / "fatigue"
    before = (live / "summary.json").read_bytes()
    (live / "stale_from_an_old_result.png").write_bytes(b"old")
    sets = ["--set", "component.enabled=false", "--set", "material.Su=310e6",
            "--set", "material.Sy=275e6"]
    capsys.readouterr()
    assert main([str(run_dir), "--quiet", *sets]) == 0
    out = capsys.readouterr().out
    assert "fails on the first cycle: life 0 km" in out
    h = settings_hash({"component.enabled": False, "material.Su": 310e6,
                       "material.Sy": 275e6})
    what_if = run_dir / f"fatigue-{h}"
    assert f"results in {what_if}" in out
    s = strict((what_if / "summary.json").read_text())
    assert s["fails_first_cycle"] is True and s["min_life_km"] == 0.0
    assert s["max_damage_per_pass"] == "inf"
    assert s["what_if"]["settings"]["material.Su"] == 310e6
    assert s["config"]["fatigue_properties"]["material"]["name"] == \
        "817M40 with Su, Sy overridden"
    assert (what_if / "damage_map.png").is_file()
    # the live results are untouched
    assert (live / "summary.json").read_bytes() == before
    # rewriting fatigue/ replaces the whole folder: the stale file is gone
    assert main([str(run_dir), "--quiet"]) == 0
    assert not (live / "stale_from_an_old_result.png").exists()
    assert strict((live / "summary.json").read_text())["min_life_km"] > 0
    assert not [p for p in run_dir.iterdir() if p.name.startswith(".")]
    # a setting that repeats the run's own is not a what-if: it rewrites fatigue/
    capsys.readouterr()
    assert main([str(run_dir), "--quiet", "--set", "influence=builtin"]) == 0
    assert f"results in {live}\n" in capsys.readouterr().out
    assert "what_if" not in strict((live / "summary.json").read_text())


def test_out_for_a_run_folder(run_dir: Path, tmp_path: Path, capsys) -> None:
    dest = tmp_path / "elsewhere"
    assert main([str(run_dir), "--quiet", "--mean-stress", "gerber", "--out", str(dest)]) == 0
    s = strict((dest / "summary.json").read_text())
    assert s["what_if"]["settings"] == {"mean_stress": "gerber"}
    assert not (run_dir / "fatigue").exists()
    # the life under both S-N methods and at the survival probability, the range given
    sm = s["sn_methods"]
    lives = [v["life_km"] for m in sm["methods"].values() for v in m.values()]
    assert len(lives) == 4 and sm["life_range_km"] == [min(lives), max(lives)]
    sh = sm["methods"]["shigley"]
    assert sh["0.975"]["life_km"] < sh["0.5"]["life_km"] == pytest.approx(s["min_life_km"])
    assert sm["methods"]["fkm"]["0.5"]["mean_stress"] == "fkm"
    assert not math.isnan(sm["methods"]["fkm"]["0.975"]["Se_pa"])


def test_channel_no_influence_file_maps_is_named(run_dir: Path, tmp_path: Path,
                                                 capsys) -> None:
    """#30 item 6: a load channel of the table that the imported influence tables do not map
    is named (with its peak load) instead of silently dropped."""
    inf = tmp_path / "inf"
    inf.mkdir()
    rng = np.random.default_rng(4)
    for name in ("bj_z.csv", "tb_mx.csv"):
        rows = ["node,x,y,z,Sx,Sy,Sz,Sxy,Syz,Szx"]
        for i in range(6):
            vals = rng.normal(0, 2e4, 6)
            rows.append(",".join([str(i + 1), f"{0.01 * i}", "0.1", "0.0",
                                  *(f"{v:.6g}" for v in vals)]))
        (inf / name).write_text("\n".join(rows) + "\n")
    sc = json.loads((run_dir / "scenario.json").read_text())
    sc["fatigue"] = {"influence": str(inf), "mapping": {
        "plant/arm/ball_joint_z": "bj_z.csv", "plant/arm/torsion_bar_mx": "tb_mx.csv"}}
    (run_dir / "scenario.json").write_text(json.dumps(sc))
    capsys.readouterr()
    assert main([str(run_dir), "--quiet"]) == 0
    out = capsys.readouterr().out
    s = strict((run_dir / "fatigue" / "summary.json").read_text())
    un = {u["channel"]: u["peak_abs"] for u in s["unmapped_channels"]}
    assert set(un) == {"plant/arm/bush_front_z", "plant/arm/bush_rear_z"}
    assert un["plant/arm/bush_rear_z"] == pytest.approx(4000.0, rel=1e-3)
    assert "no influence case for plant/arm/bush_front_z, plant/arm/bush_rear_z" in out
