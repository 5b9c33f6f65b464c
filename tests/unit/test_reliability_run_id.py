"""Issue #15 items 3 and 9: one run per folder and per run id on a bus; bad input that used
to be an internal error (exit 1), orphan nodes or a misleading message is exit 2 naming it."""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib

import pytest

from cosim import keys, safe_open
from cosim import scenario as sc
from cosim.errors import InputFileError, ScenarioError
from cosim.run_lock import FolderInUseError, RunIdInUseError, RunLock, check_run_id_free
from nodes.tyre_road import measured
from tests.conftest import CH3_STEP, ROOT, node_pids, suscosim
from tests.memory_bus import MemoryBus


def _holder(folder) -> subprocess.Popen:
    """Another process holding the folder's lock until its stdin closes."""
    code = ("import sys; from cosim.run_lock import RunLock; l = RunLock(sys.argv[1]); "
            "print('held', flush=True); sys.stdin.read()")
    p = subprocess.Popen([sys.executable, "-c", code, str(folder)], cwd=ROOT,
                         stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                         env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert p.stdout.readline().strip() == "held"
    return p


def test_a_folder_locked_by_a_live_run_is_refused_and_free_once_it_ends(tmp_path) -> None:
    holder = _holder(tmp_path)
    try:
        with pytest.raises(FolderInUseError, match=f"pid {holder.pid}") as err:
            RunLock(tmp_path)
        assert err.value.exit_code == 2
    finally:
        holder.stdin.close()
        holder.wait(timeout=10)
    RunLock(tmp_path).release()  # the kernel freed it with the process: no stale lock
    with RunLock(tmp_path):
        pass


def test_suscosim_run_into_a_folder_in_use_exits_2_before_writing(tmp_path) -> None:
    """#15 item 3: the same --out for two runs: both ended "ok" with each other's data."""
    holder = _holder(tmp_path)
    try:
        res = suscosim("run", str(CH3_STEP), "--quiet", "--out", str(tmp_path),
                       "--mode", "monolithic", "--set", "run.t_end=0.01")
    finally:
        holder.stdin.close()
        holder.wait(timeout=10)
    assert res.returncode == 2, res.stdout + res.stderr
    assert "in use by another run" in res.stderr and "Traceback" not in res.stderr
    assert not (tmp_path / "scenario.json").exists()


def test_a_run_id_live_on_the_bus_is_refused_unless_its_node_is_external() -> None:
    bus = MemoryBus()
    free = lambda rid, ext: check_run_id_free(bus, rid, ext, settle_s=0.05)  # noqa: E731
    free("r", [])
    tok = bus.token(keys.key("r", "plant", keys.ALIVE))  # a node started elsewhere
    free("r", ["plant"])
    with pytest.raises(RunIdInUseError, match="plant"):
        free("r", [])
    tok.undeclare()
    bus.token(keys.key("r", keys.ORCHESTRATOR, keys.ALIVE))  # another run's orchestrator
    with pytest.raises(RunIdInUseError, match="already live on the bus") as err:
        free("r", ["plant"])
    assert err.value.exit_code == 2
    free("other", [])


def test_run_ids_of_one_invocation_share_a_random_part() -> None:
    a, b = keys.invocation_token(), keys.invocation_token()
    assert a != b
    rid = keys.unique_run_id("sweep-" + "x" * 80, a)
    assert rid.endswith("-" + a) and len(rid) <= 64 and keys.NAME.match(rid)
    assert keys.unique_run_id("ch6-tss1-1", a) == f"ch6-tss1-1-{a}"


@pytest.mark.parametrize("setting,key", [
    ("run.h=1e-300", "run.h"),              # was: internal error OverflowError, orphans
    ("run.substeps=1000000000", "run.substeps"),  # was blamed on the recorder
    ("run.t_end=1e9", "run.t_end"),
    ("vehicle.sprung_mass=1e30", "vehicle.sprung_mass"),
    ("tyre.stiffness=-5.0", "tyre.stiffness"),
    ("road.height=50.0", "road.height"),
    ("controller.c=1e12", "controller.c"),
    ("run.stall_timeout_s=1e9", "run.stall_timeout_s"),
])
def test_out_of_range_numbers_are_refused_naming_the_key(setting, key) -> None:
    with pytest.raises(ScenarioError, match=f"'{key}'") as err:
        s = sc.load(CH3_STEP, [setting])
        sc.n_steps(s["run"]["t_end"], s["run"]["h"])
    assert err.value.exit_code == 2


def test_every_shipped_scenario_is_within_the_ranges() -> None:
    for path in sorted((ROOT / "scenarios").rglob("*.toml")):
        sc.check_ranges(tomllib.loads(path.read_text()))  # raises naming the key


def test_h_1e300_is_exit_2_and_leaves_no_node_behind(tmp_path) -> None:
    """#15 item 9: ``run.h=1e-300`` was ``internal error: OverflowError``, exit 1, and four
    orphan nodes for 33 s."""
    res = suscosim("run", str(CH3_STEP), "--quiet", "--out", str(tmp_path / "o"),
                   "--set", "run.h=1e-300", "--set", 'run.id="tiny-h"')
    assert res.returncode == 2, res.stdout + res.stderr
    assert "run.h" in res.stderr and "Traceback" not in res.stderr
    assert all(not node_pids("tiny-h", n) for n in ("plant", "tyre_road", "controller",
                                                      "recorder"))


def test_a_binary_scenario_file_is_exit_2(tmp_path) -> None:
    path = tmp_path / "s.toml"
    path.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(InputFileError, match="not a text"):
        sc.load(path)
    res = suscosim("run", str(path), "--quiet")
    assert res.returncode == 2 and "not a text" in res.stderr, res.stdout + res.stderr


def test_a_huge_road_csv_is_refused_with_a_clear_message_without_reading_it(tmp_path) -> None:
    """#15 item 9: a 200 MB road CSV took 1.9 GB of memory. Above the limit it is refused
    (a sparse file: nothing is read); below, it is read line by line into typed arrays."""
    big = tmp_path / "road.csv"
    with open(big, "wb") as f:
        f.truncate(safe_open.limit("profile") + 1)
    with pytest.raises(InputFileError, match="larger than the 256 MiB"):
        measured.read_profile_csv(big)
    ok = tmp_path / "ok.csv"
    ok.write_text("s,z\n" + "".join(f"{i * 0.01},{(i % 7) * 1e-3}\n" for i in range(20000)))
    x, zl, zr = measured.read_profile_csv(ok)
    assert x.dtype == float and len(x) == 20000 and zl[6] == pytest.approx(6e-3)
    assert (zl == zr).all() and zr is not zl
