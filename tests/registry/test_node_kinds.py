"""The node registry (cosim/node_kinds.py): what is derived from it, and a scenario's
``[nodes]`` choice of implementation, bad values named (exit 2) at preflight."""

from __future__ import annotations

import argparse
import inspect
from pathlib import Path

import pytest

from cosim import channels as ch
from cosim import keys
from cosim import node_kinds as nk
from cosim import scenario as sc
from cosim.errors import ScenarioError
from orchestrator import node_main
from orchestrator.placement import core_layout
from orchestrator.runner import resolve

from ..conftest import CH3_STEP, ROOT

REALISTIC = ROOT / "scenarios" / "ch4_qvm_realistic_bump_pothole.toml"


def _ch3(**nodes: object) -> dict:
    scenario = sc.load(CH3_STEP)
    if nodes:
        scenario[nk.SECTION] = dict(nodes)
    return scenario


def test_the_run_constants_are_the_registry_s() -> None:
    assert ch.NODES == ("plant", "tyre_road", "controller", "recorder") == nk.always()
    assert ch.COUPLED == ("plant", "tyre_road", "controller") == nk.names(nk.COUPLED)
    assert ch.OPTIONAL_NODES == ("fatigue",) == nk.names(nk.OPTIONAL)
    assert {k.role for k in nk.KINDS} <= set(nk.ROLES)
    with pytest.raises(AttributeError):
        ch.NO_SUCH_THING  # noqa: B018


def test_channel_names_of_the_registry_are_the_protocol_s() -> None:
    """The registry spells names as strings (it imports nothing): they must be the ones the
    nodes use (cosim.channels, cosim.keys)."""
    known = {ch.STATE, ch.RESPONSE, ch.ARM, ch.FORCE, ch.LOADS, ch.DAMAGE, ch.COUPLING,
             keys.RECORDS, keys.STEP}
    known |= set(ch.CORNER_ARMS)  # the four-corner vehicle's arm_FL .. arm_RR (#31)
    known.add(ch.UPPER_ARM)  # the double wishbone's upper arm (#26 item 5)
    for k in nk.KINDS:
        keys.check_name("kind", k.name)
        assert set(k.writes) <= known, k.name
        for node, channel in k.reads:
            assert channel in known and (node == "*" or node in nk.BY_NAME), (k.name, node)
    assert nk.inputs("fatigue") == (ch.LOAD_CHANNEL,)  # straight from the plant (#28 item 4)
    assert nk.inputs("controller") == nk.inputs("tyre_road") == ((ch.PLANT, ch.STATE),)


def test_every_entry_and_check_of_the_registry_loads() -> None:
    for k in nk.KINDS:
        for impl in (k.impl, *k.alternatives.values()):
            fn = nk.load(impl.entry)
            if inspect.isclass(fn):  # a stepped node (cosim.stepped), as a user's may be
                assert callable(fn.step) and \
                    list(inspect.signature(fn).parameters)[:2] == ["scenario", "start"]
            else:
                assert list(inspect.signature(fn).parameters)[:2] == ["part", "scenario"]
            if impl.check is not None:
                check = nk.load(impl.check.entry)
                assert len(inspect.signature(check).parameters) == 1 + len(impl.check.takes)


def test_who_reads_what_is_derived() -> None:
    assert nk.producers() == ch.COUPLED  # the recorder journals every coupled node
    assert nk.force_sources() == (("tyre_road", ("F_t", "k_t")),
                                  ("controller", ("F_d", "c_eff")))
    assert nk.path_keys() == sc.PATH_KEYS  # cosim/scenario.py resolves the same paths


def test_node_main_knows_every_kind_and_its_module() -> None:
    assert node_main.NODE_MODULES == {
        "plant": "nodes.plant.node", "tyre_road": "nodes.tyre_road.node",
        "controller": "nodes.controller.node", "recorder": "nodes.recorder.node",
        "fatigue": "nodes.fatigue.node"}
    with pytest.raises(SystemExit) as exc:
        node_main.main(["no_such_kind", "--run", "r"])
    assert exc.value.code == 2


@pytest.mark.parametrize("n, want", [
    (2, {"plant": 0, "tyre_road": 1, "controller": 0, "recorder": 1, "fatigue": 1}),
    (3, {"plant": 0, "tyre_road": 1, "controller": 2, "recorder": 0, "fatigue": 0}),
    (4, {"plant": 0, "tyre_road": 1, "controller": 2, "recorder": 3, "fatigue": 3}),
    (8, {"plant": 0, "tyre_road": 1, "controller": 2, "recorder": 3, "fatigue": 3}),
])
def test_placement_is_the_registry_s_table(n: int, want: dict) -> None:
    cores = [10 + i for i in range(n)]
    assert core_layout(nk.names(), cores) == {k: cores[i] for k, i in want.items()}


def test_resolve_lists_the_nodes_from_the_registry() -> None:
    assert resolve(_ch3())["run"]["nodes"] == list(ch.NODES)
    realistic = resolve(sc.load(REALISTIC))  # the live fatigue node joins (arm loads)
    assert realistic["run"]["nodes"] == [*ch.NODES, "fatigue"]
    ref = sc.load(REALISTIC)
    ref["run"]["mode"] = "reference"
    assert "fatigue" not in resolve(ref)["run"]["nodes"]


def test_an_implementation_is_picked_per_kind() -> None:
    assert nk.implementation("controller", _ch3()) is nk.kind("controller").impl
    assert nk.implementation("controller", _ch3(controller="native")) is \
        nk.kind("controller").impl
    assert nk.implementation("controller", _ch3(controller="fmu")) is \
        nk.kind("controller").alternatives["fmu"]
    user = nk.implementation("controller", _ch3(controller="argparse:ArgumentParser"))
    assert user.entry == "argparse:ArgumentParser" and user.check is None
    assert node_main.node_callable("recorder", _ch3()) is not None
    assert nk.load("argparse:ArgumentParser") is argparse.ArgumentParser


@pytest.mark.parametrize("nodes, key, words", [
    ({"gearbox": "native"}, "nodes.gearbox", "unknown kind 'gearbox'"),
    ({"controller": "no_such_pkg.mod:Ctl"}, "nodes.controller", "cannot import 'no_such_pkg.mod'"),
    ({"controller": "argparse:NoSuchClass"}, "nodes.controller", "has no 'NoSuchClass'"),
    ({"controller": "argparse:SUPPRESS"}, "nodes.controller", "a class or function"),
    ({"controller": "simulink"}, "nodes.controller", "one of 'native', 'fmu'"),
    ({"plant": "fmu"}, "nodes.plant", "one of 'native' or"),
    ({"controller": 3}, "nodes.controller", "'package.module:Class'"),
    ({"controller": ":Ctl"}, "nodes.controller", "'package.module:Class'"),
])
def test_bad_node_choices_are_exit_2_naming_the_key(nodes, key, words) -> None:
    with pytest.raises(ScenarioError) as exc:
        resolve(_ch3(**nodes))
    assert exc.value.key == key and exc.value.exit_code == 2
    assert words in str(exc.value), str(exc.value)


def test_nodes_must_be_a_table() -> None:
    scenario = _ch3()
    scenario[nk.SECTION] = "controller"
    with pytest.raises(ScenarioError, match="nodes"):
        resolve(scenario)


def test_a_user_module_that_raises_on_import_is_named(tmp_path: Path, monkeypatch) -> None:
    (tmp_path / "broken_node.py").write_text("raise RuntimeError('half written')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(ScenarioError, match="raised RuntimeError: half written") as exc:
        resolve(_ch3(controller="broken_node:Ctl"))
    assert exc.value.key == "nodes.controller"


def test_a_user_node_s_preflight_runs_with_the_facts(tmp_path: Path, monkeypatch) -> None:
    (tmp_path / "picky_node.py").write_text(
        "from cosim.errors import ScenarioError\n"
        "class Picky:\n"
        "    seen = None\n"
        "    @staticmethod\n"
        "    def preflight(scenario, facts):\n"
        "        Picky.seen = dict(facts)\n"
        "        if scenario['controller'].get('c', 0) > 1000:\n"
        "            raise ScenarioError('controller.c', scenario['controller']['c'], "
        "'at most 1000 for Picky')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(ScenarioError, match="at most 1000 for Picky"):
        resolve(_ch3(controller="picky_node:Picky"))
    import picky_node

    assert picky_node.Picky.seen["n_corners"] == 1 and "duration_s" in picky_node.Picky.seen
    scenario = _ch3(controller="picky_node:Picky")
    scenario["controller"] = {"c": 800.0}  # a user's section: the native law is not built
    assert resolve(scenario)["run"]["nodes"] == list(ch.NODES)


def test_the_fmu_alternative_takes_the_fmu_law_only() -> None:
    scenario = _ch3(controller="fmu")
    with pytest.raises(ScenarioError) as exc:  # the Ch3 law is "passive"
        resolve(scenario)
    assert exc.value.key == "controller.law" and "fmu" in exc.value.expected
    scenario = _ch3(controller="fmu")
    scenario["controller"] = {"fmu": "/no/such/law.fmu"}  # law filled in, FMU opened
    with pytest.raises(Exception, match="no such FMU file"):
        resolve(scenario)
    assert scenario["controller"]["law"] == "fmu"


def test_suscosim_run_refuses_a_bad_node_choice_before_any_process(tmp_path: Path) -> None:
    """Through the real CLI: a scenario file's [nodes] with a module that is not there is
    exit 2 naming nodes.controller, and no node was started (no logs)."""
    assert nk.SECTION in sc.SECTIONS
    from ..conftest import suscosim

    path = tmp_path / "mine.toml"
    path.write_text(CH3_STEP.read_text() + '\n[nodes]\ncontroller = "no_such_lab.dampers:Mine"\n')
    res = suscosim("run", str(path), "--out", str(tmp_path / "run"), "--quiet", timeout=120)
    assert res.returncode == 2, res.stdout + res.stderr
    assert "nodes.controller" in res.stderr and "cannot import 'no_such_lab.dampers'" in res.stderr
    assert "Traceback" not in res.stderr
    assert not (tmp_path / "run" / "logs").exists()


def test_a_fact_a_later_check_needs_but_no_implementation_gave_is_named() -> None:
    """A user's plant (a class without a preflight) gives no n_corners: the controller's
    check, which takes it, cannot run; that is said, not a TypeError."""
    with pytest.raises(ScenarioError, match="gives n_corners \\(the check of controller"):
        resolve(_ch3(plant="argparse:ArgumentParser"))


def test_a_relative_fmu_path_is_relative_to_the_scenario_file(tmp_path: Path) -> None:
    """``controller.fmu`` is a path key of the controller kind: relative to the scenario's
    folder, like the road file, not to where suscosim was started."""
    folder = tmp_path / "study"
    folder.mkdir()
    path = folder / "s.toml"
    text = CH3_STEP.read_text().replace("[controller]", '[controller]\nfmu = "laws/t.fmu"', 1)
    path.write_text(text)
    scenario = sc.load(path)
    assert scenario["controller"]["fmu"] == str(folder / "laws" / "t.fmu")
    assert ("controller", "fmu") in sc.PATH_KEYS
