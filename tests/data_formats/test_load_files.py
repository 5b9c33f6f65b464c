"""#20: a measured load file goes through the same fatigue chain as a run's table: a rig's
CSV (its own channel names, kN, one axis flipped) mapped with --map gives the run's life; a
malformed file, a missing channel or a wrong unit is exit 2 naming the file."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from cosim.table import read_table

from ..conftest import suscosim
from .conftest import cli

pytestmark = pytest.mark.integration


def test_rig_csv_with_own_names_and_kn_mapped_gives_the_runs_life(pave_run: Path,
                                                                  tmp_path: Path,
                                                                  capsys) -> None:
    table = read_table(pave_run / "table.parquet")
    arm = [c for c in table if c.startswith("plant/arm/")]
    rig = tmp_path / "rig.csv"
    cols, maps = [table["t"]], []
    header = ["time [s]"]
    for i, c in enumerate(arm):
        short = c.rsplit("/", 1)[1]
        name = f"CH{i:02d}"
        moment = short.endswith("_mx")
        flip = short == "ball_joint_z"  # the rig's z axis points down here
        header.append(f"{name} [{'kN m' if moment else 'kN'}]")
        cols.append((-1 if flip else 1) * table[c] / 1000.0)
        maps += ["--map", f"{name}={short}" + ("*-1" if flip else "")]
    with open(rig, "w") as fh:
        fh.write("# a rig export: channel names of its own, kN\n" + ",".join(header) + "\n")
        for row in zip(*(x.tolist() for x in cols), strict=True):
            fh.write(",".join(repr(v) for v in row) + "\n")
    rc, out, err = cli(capsys, "fatigue", str(rig), "--scenario", str(pave_run), *maps)
    assert rc == 0, out + err
    mine = json.loads((tmp_path / "rig.csv.fatigue" / "summary.json").read_text())
    base = json.loads((pave_run / "fatigue" / "summary.json").read_text())
    assert mine["missing_channels"] == []
    assert mine["critical_node_id"] == base["critical_node_id"]
    assert mine["min_life_km"] == pytest.approx(base["min_life_km"], rel=1e-9)
    # without the flip the ball joint's vertical load is reversed: another life
    rc, out, err = cli(capsys, "fatigue", str(rig), "--scenario", str(pave_run),
                       *[m.replace("*-1", "") for m in maps], "--out", str(tmp_path / "f"))
    assert rc == 0, out + err
    flipped = json.loads((tmp_path / "f" / "summary.json").read_text())
    assert flipped["min_life_km"] != pytest.approx(base["min_life_km"], rel=1e-3)


def test_defaults_without_a_scenario_need_a_track_length(tmp_path: Path, capsys) -> None:
    t = np.arange(0, 1.0, 1e-3)
    f = tmp_path / "loads.csv"
    rows = "".join(f"{a!r},{3000 * math.sin(40 * a)!r}\n" for a in t.tolist())
    f.write_text("t,ball_joint_z\n" + rows)
    rc, out, err = cli(capsys, "fatigue", str(f))
    assert rc == 2 and "track_length_m" in err, out + err
    rc, out, err = cli(capsys, "fatigue", str(f), "--set", "track_length_m=9.4")
    assert rc == 0, out + err
    assert "no load given for " in out and "plant/arm/ball_joint_x" in out
    s = json.loads((tmp_path / "loads.csv.fatigue" / "summary.json").read_text())
    assert "plant/arm/ball_joint_x" in s["missing_channels"]
    assert "plant/arm/ball_joint_z" not in s["missing_channels"]
    assert s["track_length_m"] == 9.4 and s["n_samples"] == t.size


@pytest.mark.parametrize("name, content, says", [
    ("garbage.rsp", b"\x00\x01 not an RPC III file" * 40, "not a readable RPC III file"),
    ("garbage.mf4", b"MDF     4.10    " + b"\0" * 80, "not a readable MDF file"),
    ("short.csv", b"t,ball_joint_z\n0,1\n0.001\n", "expected 2 fields"),
    ("words.csv", b"t,ball_joint_z\n0,1\n0.001,lots\n", "non-numeric"),
    ("notime.csv", b"x,ball_joint_z\n0,1\n1,2\n", "no time column"),
    ("names.csv", b"t,Fz\n0,1\n0.001,2\n", "no channel maps to an arm load channel"),
    ("units.csv", b"t,ball_joint_z [mm]\n0,1\n0.001,2\n", "unit 'mm'"),
    ("back.csv", b"t,ball_joint_z\n0,1\n0,2\n", "not strictly increasing"),
    ("loads.xlsx", b"PK", "unknown load file type"),
])
def test_malformed_load_file_exit_2_naming_it(tmp_path: Path, name: str, content: bytes,
                                              says: str, capsys) -> None:
    f = tmp_path / name
    f.write_bytes(content)
    rc, out, err = cli(capsys, "fatigue", str(f), "--set", "track_length_m=10")
    assert rc == 2, out + err
    assert str(f) in err and says in err


def test_malformed_load_file_from_the_command_line(tmp_path: Path) -> None:
    f = tmp_path / "torn.rsp"
    f.write_bytes(b"FORMAT" + b"\0" * 26 + b"BINARY" + b"\0" * 90)
    res = suscosim("fatigue", str(f), "--set", "track_length_m=10")
    assert res.returncode == 2, res.stdout + res.stderr
    assert str(f) in res.stderr and "Traceback" not in res.stderr
    res = suscosim("fatigue", str(tmp_path / "nowhere.mf4"), "--map", "a=b")
    assert res.returncode == 2 and "nowhere.mf4" in res.stderr


@pytest.mark.parametrize("bad, says", [
    ("1e308", ["'plant/arm/ball_joint_z' sample 123", "beyond the plausible"]),
    ("1e12", ["'plant/arm/ball_joint_z' sample 123", "beyond the plausible"]),
    # the CSV reader itself refuses these, naming the line (header + 123 + 1)
    ("nan", ["loads.csv:125", "non-finite"]), ("inf", ["loads.csv:125", "non-finite"])])
def test_non_physical_load_sample_is_exit_2_naming_channel_and_sample(tmp_path: Path,
                                                                       bad: str,
                                                                       says: list[str],
                                                                       capsys) -> None:
    """#30 item 14: one absurd sample is bad input naming the channel and the sample, not
    a life with a NaN in summary.json (1e308) or an internal ValueError (1e12)."""
    t = np.arange(0, 0.5, 1e-3)
    f = tmp_path / "loads.csv"
    vals = [repr(3000 * math.sin(40 * a)) for a in t.tolist()]
    vals[123] = bad
    f.write_text("t,ball_joint_z\n" + "".join(f"{a!r},{v}\n" for a, v in
                                               zip(t.tolist(), vals, strict=True)))
    rc, out, err = cli(capsys, "fatigue", str(f), "--set", "track_length_m=5")
    assert rc == 2, out + err
    assert all(w in err for w in says), err
    assert "internal error" not in err
    assert not (tmp_path / "loads.csv.fatigue").exists()


def test_summary_is_strict_json_and_every_output_written(tmp_path: Path, capsys) -> None:
    """summary.json parses with NaN/Infinity refused; the batch outputs are in the folder
    (#30 item 5) and the VTU holds the CSV's damage per node."""
    import csv

    import meshio

    t = np.arange(0, 0.5, 1e-3)
    f = tmp_path / "loads.csv"
    f.write_text("t,ball_joint_z\n" + "".join(f"{a!r},{4000 + 3000 * math.sin(40 * a)!r}\n"
                                               for a in t.tolist()))
    rc, out, err = cli(capsys, "fatigue", str(f), "--set", "track_length_m=5")
    assert rc == 0, out + err
    d = tmp_path / "loads.csv.fatigue"

    def refuse(x: str) -> None:
        raise AssertionError(f"non-strict JSON constant {x}")

    s = json.loads((d / "summary.json").read_text(), parse_constant=refuse)
    for name in s["outputs"]:
        assert (d / name).is_file(), name
    rows = list(csv.DictReader(open(d / "damage_per_node.csv")))
    vtu = meshio.read(d / "damage.vtu")
    assert len(vtu.points) == len(rows)
    np.testing.assert_allclose(vtu.point_data["damage_per_pass"],
                               [float(r["damage_per_pass"]) for r in rows], rtol=1e-6)
    hist = list(csv.DictReader(open(d / "critical_stress.csv")))
    assert len(hist) == t.size
    # the critical node's equivalent-stress range in its history is the CSV's largest range
    eq = np.array([float(r[list(r)[-1]]) for r in hist])
    crit = max(rows, key=lambda r: float(r["damage_per_pass"]))
    assert np.ptp(eq) == pytest.approx(float(crit["eq_range_max_pa"]), rel=1e-5)
    assert s["sn_methods"]["life_range_km"][0] <= s["min_life_km"] <= \
        s["sn_methods"]["life_range_km"][1]
