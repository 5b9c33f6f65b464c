"""``[sweep] fork_at = T`` (issue #29 item 5): the points of a group share one parent run and
fork from its checkpoint at T. Real distributed runs (checkpoints need them) of the Ch 3
quarter car.

Byte for byte means the files' bytes: a point whose controller is the parent's (the base's)
has the parent's ``table.parquet`` and ``table.csv``; the other points' rows before T are the
parent's rows, and each whole table is the one ``suscosim run --fork`` gives by hand.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from ..conftest import COARSE_ARM, ROOT, suscosim

CH3 = ROOT / "scenarios" / "ch3_step_quarter_car.toml"
T, H, T_END = 1.0, 0.001, 1.5
K, N = round(T / H), round(T_END / H)

SWEEP = f"""
[sweep]
name = "fk"
base = "{CH3}"
jobs = 2
fork_at = {T}
[sweep.set]
"run.t_end" = {T_END}
"run.mode" = "distributed"
"run.stall_timeout_s" = 30.0
[sweep.grid.damper]
same = {{ "controller.c" = 1500.0 }}                          # the base's own damper
soft = {{ controller = {{ law = "passive", c = 1000.0 }} }}
hard = {{ "controller.c" = 3000.0 }}
"""


def _table(path: Path):
    return pq.read_table(path / "table.parquet").to_pandas()


@pytest.fixture(scope="module")
def swept(tmp_path_factory) -> tuple[Path, Path, str]:
    root = tmp_path_factory.mktemp("sweep_fork")
    sweep_file = root / "fk.toml"
    sweep_file.write_text(SWEEP)
    out = root / "out"
    r = suscosim("sweep", str(sweep_file), "--out", str(out), timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    return sweep_file, out, r.stdout + r.stderr


def test_one_parent_and_its_forks_share_the_prefix_byte_for_byte(swept, tmp_path):
    _, out, _ = swept
    parents = sorted((out / "parents").iterdir())
    assert [p.name for p in parents] == ["fk-parent"]
    parent = parents[0]
    assert sorted(c.name for c in (parent / "checkpoints").iterdir()) == [f"k{K:06d}"]
    # the base's controller is the parent's: that point's fork continues it byte for byte
    for f in ("table.parquet", "table.csv"):
        assert (out / "runs" / "fk-same" / f).read_bytes() == (parent / f).read_bytes(), f
    ptab = _table(parent)
    assert len(ptab) == N + 1
    state = [c for c in ptab.columns if c.startswith("plant/state/")]
    for name in ("soft", "hard"):
        run = out / "runs" / f"fk-{name}"
        resumed = json.loads((run / "scenario.json").read_text())["run"]["resume"]
        assert resumed["k"] == K and Path(resumed["parent"]) == parent  # it did fork
        ftab = _table(run)
        assert len(ftab) == N + 1
        assert ptab.iloc[:K].equals(ftab.iloc[:K]), name  # the prefix: the parent's rows
        assert ptab.loc[K, state].equals(ftab.loc[K, state])  # and the state at T
        assert ftab.loc[K, "controller/force/F_d"] != ptab.loc[K, "controller/force/F_d"]
    # the whole table is the fork a user gets by hand from the same parent
    by_hand = tmp_path / "by_hand"
    r = suscosim("run", "--fork", f"{parent}@{T}", "--out", str(by_hand), "--quiet",
                 "--set", "controller.c=1000.0")
    assert r.returncode == 0, r.stdout + r.stderr
    for f in ("table.parquet", "table.csv"):
        assert (out / "runs" / "fk-soft" / f).read_bytes() == (by_hand / f).read_bytes(), f


def test_the_sweep_says_what_it_saved_and_what_forking_means(swept):
    _, out, text = swept
    doc = json.loads((out / "fork.json").read_text())
    n_points = 3
    steps = doc["steps"]
    assert steps["plain"] == n_points * N
    assert steps["prefix_not_simulated_again"] == n_points * K
    assert steps["simulated"] == N + n_points * (N - K)
    assert steps["saved"] == n_points * K - N == 1500
    assert steps["saved_share"] == pytest.approx(1500 / 4500)
    # the figures are those of the run folders: each fork's table has N + 1 rows, its
    # journal starts at the parent's k
    runs = [out / "runs" / f"fk-{n}" for n in ("same", "soft", "hard")]
    assert sum(json.loads((r / "summary.json").read_text())["n_steps"] for r in runs) == \
        steps["plain"]
    assert [p["id"] for p in doc["parents"]] == ["fk-parent"]
    assert doc["parents"][0]["points"] == ["fk-same", "fk-soft", "fk-hard"]
    assert doc["points"] == doc["points_ok"] == n_points
    wall = doc["wall_s"]  # from the runs' summary.json (its size is not asserted)
    walls = [json.loads((r / "summary.json").read_text())["wall_s"] for r in runs]
    assert wall["forks"] == pytest.approx(sum(walls))
    assert wall["total"] == pytest.approx(wall["parents"] + wall["forks"])
    assert wall["plain_estimate"] == pytest.approx(n_points * wall["parents"])
    assert doc["elapsed_s"] > 0
    assert "acts only from t = fork_at on" in doc["semantics"]
    assert "1500 saved (33.3 %)" in text and "3000 prefix steps not simulated again" in text
    assert "its own controller acts only from there on" in text
    with open(out / "results.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert {r["parent"] for r in rows} == {"fk-parent"}
    assert {float(r["fork_at"]) for r in rows} == {T}
    plan = json.loads((out / "sweep.json").read_text())["fork"]
    assert plan["fork_at"] == T and plan["parents"][0]["k"] == K


def test_a_rerun_is_done_and_a_new_fork_at_makes_the_points_stale(swept, tmp_path):
    sweep_file, out, _ = swept
    parent_table = out / "parents" / "fk-parent" / "table.parquet"
    mtime = parent_table.stat().st_mtime_ns
    r = suscosim("sweep", str(sweep_file), "--out", str(out))
    assert r.returncode == 0, r.stdout + r.stderr
    assert "0 to run (3 already done)" in r.stdout
    assert parent_table.stat().st_mtime_ns == mtime
    moved = sweep_file.read_text().replace(f"fork_at = {T}", "fork_at = 0.5")
    other = tmp_path / "fk.toml"
    other.write_text(moved)
    r = suscosim("sweep", str(other), "--out", str(out), "--list")
    assert r.returncode == 0, r.stdout + r.stderr
    listed = [ln.split() for ln in r.stdout.splitlines() if ln.startswith("  fk-")]
    assert listed and all(ln[1] == "todo" for ln in listed), r.stdout


def test_groups_a_road_or_a_step_cannot_fork_across(tmp_path):
    text = SWEEP.replace('[sweep.grid.damper]', '[sweep.grid]\n"road.height" = [0.02, 0.03]\n'
                         '[sweep.grid.damper]')
    text += 'fine = { "controller.c" = 3000.0, "run.h" = 0.0005 }\n'
    f = tmp_path / "g.toml"
    f.write_text(text)
    r = suscosim("sweep", str(f), "--out", str(tmp_path / "o"), "--list")
    assert r.returncode == 0, r.stdout + r.stderr
    parents = {ln.split()[0]: ln for ln in r.stdout.splitlines()
               if ln.startswith("  fk-parent")}
    assert sorted(parents) == ["fk-parent-0.02", "fk-parent-0.02-fine", "fk-parent-0.03",
                               "fk-parent-0.03-fine"]
    assert "of 3 point(s)" in parents["fk-parent-0.02"]
    assert "of 1 point(s), checkpoint k = 2000" in parents["fk-parent-0.03-fine"]
    assert "(fork of fk-parent-0.03)" in next(ln for ln in r.stdout.splitlines()
                                             if ln.startswith("  fk-0.03-soft"))


@pytest.mark.parametrize("value, why", [
    ("0.0015", "not a whole number of steps of h = 0.001 s"),
    ("2.0", "not before the end of the run"),
    ("1.5", "not before the end of the run"),
    ("0.0", "a time in seconds > 0"),
    ('"1.0"', "a time in seconds > 0"),
])
def test_a_bad_fork_at_is_refused_naming_it(tmp_path, value, why):
    f = tmp_path / "bad.toml"
    f.write_text(SWEEP.replace(f"fork_at = {T}", f"fork_at = {value}"))
    r = suscosim("sweep", str(f), "--out", str(tmp_path / "o"))
    assert r.returncode == 2, r.stdout + r.stderr
    assert "[sweep] fork_at" in r.stderr and why in r.stderr, r.stderr
    assert "Traceback" not in r.stderr
    assert not (tmp_path / "o" / "parents").exists()  # nothing started


def test_fork_at_is_refused_with_the_dask_executor(tmp_path):
    f = tmp_path / "fk.toml"
    f.write_text(SWEEP)
    r = suscosim("sweep", str(f), "--out", str(tmp_path / "o"), "--executor", "dask",
                 "--scheduler", "tcp://127.0.0.1:1")
    assert r.returncode == 2 and "fork_at works with the local executor" in r.stderr, r.stderr


def test_fatigue_works_on_the_forks_run_folders(tmp_path):
    """The realistic corner with the live fatigue node (5 m of pave): the forks' fatigue
    results are those of their own folders; the fork whose damper is the base's has the
    parent's damage per node and lives, byte for byte (its fatigue engine continued)."""
    ch6 = ROOT / "scenarios" / "thesis" / "ch6_realistic_qvm.toml"
    f = tmp_path / "c6.toml"
    f.write_text(f"""
[sweep]
name = "c6f"
base = "{ch6}"
jobs = 2
fatigue = true
fork_at = 0.25
[sweep.set]
"road.length_m" = 5.0
"run.mode" = "distributed"
"fatigue.influence" = "{COARSE_ARM}"
[sweep.grid.strategy]
passive = {{ controller = {{ law = "passive", c = 3800.0, velocity = "damper" }} }}
firm = {{ controller = {{ law = "passive", c = 6000.0, velocity = "damper" }} }}
""")
    out = tmp_path / "out"
    r = suscosim("sweep", str(f), "--out", str(out), timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    parent = out / "parents" / "c6f-parent"
    for name in ("damage_per_node.csv", "summary.json"):
        assert (out / "runs" / "c6f-passive" / "fatigue" / name).read_bytes() == \
            (parent / "fatigue" / name).read_bytes(), name
    with open(out / "results.csv") as fh:
        rows = {r["point"]: r for r in csv.DictReader(fh)}
    firm = json.loads((out / "runs" / "c6f-firm" / "fatigue" / "summary.json").read_text())
    assert float(rows["c6f-firm"]["life_km"]) == pytest.approx(firm["min_life_km"], rel=1e-9)
    assert rows["c6f-firm"]["life_km"] != rows["c6f-passive"]["life_km"]
    doc = json.loads((out / "fork.json").read_text())
    k, n = 500, 1059  # 0.25 s and 5 m at 34 km/h (0.529 s) of h = 0.5 ms
    assert doc["steps"]["saved"] == 2 * k - n < 0  # one law besides the base's: no gain
    assert "-59 saved" in r.stdout
