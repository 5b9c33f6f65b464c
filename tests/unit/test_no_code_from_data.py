"""The product reads data, never code (issue #43): no pickle, marshal or eval anywhere in
cosim/, nodes/, orchestrator/, and a module imported by a name only where the name is the
user's own plugin in the scenario they run (a run folder's scenario that names code is
refused on resume and fork: tests below)."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import pytest

from cosim.checkpoint import CheckpointError
from orchestrator import resume as rs

ROOT = Path(__file__).resolve().parents[2]
PRODUCT = ("cosim", "nodes", "orchestrator")
BANNED_MODULES = {"pickle", "marshal", "shelve", "dill", "cloudpickle", "joblib", "copyreg"}
BANNED_CALLS = {"eval", "exec", "__import__", "read_pickle"}
IMPORT_BY_NAME = {
    # (file, function): why the name is not read from a data file
    ("cosim/node_kinds.py", "load"): "[nodes] kind = 'pkg.mod:Class' of the user's scenario",
    ("nodes/controller/registry.py", "lookup"): "controller.law = 'pkg.mod:function' (same)",
    ("nodes/controller/registry.py", "discover"): "the package's own modules (pkgutil)",
    ("orchestrator/cli.py", "_delegate"): "a constant table of subcommands",
    ("orchestrator/export_fmu.py", "_law_module_file"): "the law the user exports (argv)",
}


def _findings(path: Path, rel: str = "") -> list[str]:
    tree = ast.parse(path.read_text(), str(path))
    rel = rel or path.relative_to(ROOT).as_posix()
    out: list[str] = []
    funcs = [n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)]

    def owner(node: ast.AST) -> str:
        inside = [f for f in funcs if f.lineno <= node.lineno <= (f.end_lineno or 0)]
        return max(inside, key=lambda f: f.lineno).name if inside else "<module>"

    for node in ast.walk(tree):
        if isinstance(node, ast.Import | ast.ImportFrom):
            names = [a.name for a in node.names]
            if isinstance(node, ast.ImportFrom) and node.module:
                names.append(node.module)
            out += [f"{rel}:{node.lineno} imports {n}" for n in names
                    if n.split(".")[0] in BANNED_MODULES]
        elif isinstance(node, ast.Call):
            f = node.func
            name = f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) \
                else ""
            if name in BANNED_CALLS:
                out.append(f"{rel}:{node.lineno} calls {name}")
            if name == "import_module" and (rel, owner(node)) not in IMPORT_BY_NAME:
                out.append(f"{rel}:{node.lineno} imports a module by name in {owner(node)}")
            for kw in node.keywords:
                if kw.arg == "allow_pickle" and not (isinstance(kw.value, ast.Constant)
                                                     and kw.value.value is False):
                    out.append(f"{rel}:{node.lineno} allow_pickle is not False")
    return out


def test_the_product_source_holds_no_pickle_marshal_eval_or_import_by_data_name():
    files = [p for d in PRODUCT for p in (ROOT / d).rglob("*.py")]
    assert len(files) > 100  # the scan sees the product
    found = [f for p in files for f in _findings(p)]
    assert found == []


def test_the_scan_finds_what_it_bans(tmp_path):
    bad = tmp_path / "probe.py"
    bad.write_text("import pickle\nimport importlib\nx = eval('1')\n"
                   "def f(n):\n    return importlib.import_module(n)\n"
                   "import numpy as np\nnp.load('a', allow_pickle=True)\n")
    got = _findings(bad, "nodes/probe.py")
    assert sorted(g.split(" ", 1)[1] for g in got) == [
        "allow_pickle is not False", "calls eval", "imports a module by name in f",
        "imports pickle"]


@pytest.mark.parametrize("section,value", [
    ("nodes", {"controller": "evil_mod:Node"}),
    ("controller", {"law": "evil_mod:law"}),
])
def test_a_run_folder_whose_scenario_names_code_is_refused(tmp_path, monkeypatch, section,
                                                            value):
    run = tmp_path / "run"
    run.mkdir()
    (run / "evil_mod.py").write_text(f"open({str(tmp_path / 'pwned')!r}, 'w')\n")
    (run / "scenario.json").write_text(json.dumps({"run": {"id": "r", "dir": str(run)},
                                                   section: value}))
    monkeypatch.chdir(run)
    monkeypatch.delenv(rs.TRUST_CODE_ENV, raising=False)
    with pytest.raises(CheckpointError, match="names code to run") as e:
        rs.resume_scenario(run)
    assert e.value.exit_code == 2 and rs.TRUST_CODE_ENV in str(e.value)
    with pytest.raises(CheckpointError, match="evil_mod"):
        rs.fork_scenario(f"{run}@1.0", [], None, lambda s, o: s)
    assert not (tmp_path / "pwned").exists()
