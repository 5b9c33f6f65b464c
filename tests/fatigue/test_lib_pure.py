"""nodes/fatigue/lib/ is pure numerics (issue #42 item 3): it imports nothing of the bus, the
run folder or the rest of the product, and opens, reads or writes no file (an AST scan of its
source, as tests/unit/test_no_code_from_data.py does, and an import in a clean interpreter)."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
LIB = ROOT / "nodes" / "fatigue" / "lib"
BANNED_PACKAGES = {"cosim", "orchestrator", "nodes", "zenoh"}
"""Absolute imports of these are the node's side (cosim.bus, participant, journal, run_folder,
...); the library imports its own modules relatively (one level)."""
IO_MODULES = {"os", "io", "pathlib", "shutil", "tempfile", "csv", "tomllib", "subprocess",
              "socket", "glob", "zipfile", "gzip", "pickle", "sqlite3", "pyarrow", "meshio",
              "gmsh", "matplotlib"}
IO_CALLS = {"open", "read_text", "write_text", "read_bytes", "write_bytes", "mkdir", "unlink",
            "rename", "rmdir", "touch", "save", "savez", "savez_compressed", "savetxt", "load",
            "loadtxt", "genfromtxt", "fromfile", "tofile", "dump"}
"""Calls that open a file (``json.dumps`` to a string is not one: ``dump`` to a file is)."""


def findings(source: str, rel: str) -> list[str]:
    """What in ``source`` is not pure: banned imports, relative imports leaving the package,
    calls that touch files."""
    out: list[str] = []
    for node in ast.walk(ast.parse(source, rel)):
        if isinstance(node, ast.ImportFrom) and node.level > 1:
            out.append(f"{rel}:{node.lineno} imports from outside lib ({'.' * node.level})")
        elif isinstance(node, ast.Import | ast.ImportFrom):
            mods = [a.name for a in node.names] if isinstance(node, ast.Import) else (
                [node.module] if node.module and node.level == 0 else [])
            out += [f"{rel}:{node.lineno} imports {m}" for m in mods
                    if m.split(".")[0] in BANNED_PACKAGES | IO_MODULES]
        elif isinstance(node, ast.Call):
            f = node.func
            name = f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) \
                else ""
            if name in IO_CALLS:
                out.append(f"{rel}:{node.lineno} calls {name}")
    return out


def test_the_scan_finds_io_and_bus_imports() -> None:
    bad = ("from cosim.bus import Bus\nimport cosim.run_folder\nfrom ..config import X\n"
           "import pathlib\nfh = open('x')\nnp.savez('y', a=1)\np.write_text('z')\n")
    got = findings(bad, "bad.py")
    assert [g.split(" ", 1)[1] for g in got] == [
        "imports cosim.bus", "imports cosim.run_folder", "imports from outside lib (..)",
        "imports pathlib", "calls open", "calls savez", "calls write_text"]
    assert findings("from .counting import Cycles\ns = json.dumps({})\n", "ok.py") == []


def test_lib_has_no_bus_and_no_file_io() -> None:
    files = sorted(LIB.glob("*.py"))
    assert len(files) > 15, files  # the package is where this test thinks it is
    bad = [f for p in files for f in findings(p.read_text(), p.relative_to(ROOT).as_posix())]
    assert bad == []


def test_lib_imports_nothing_of_the_product() -> None:
    """Importing every lib module in a fresh interpreter loads no cosim/orchestrator module
    and no node code outside the library (transitively, not only the import lines)."""
    code = ("import importlib, pkgutil, sys\nimport nodes.fatigue.lib as L\n"
            "for m in pkgutil.iter_modules(L.__path__):\n"
            "    importlib.import_module('nodes.fatigue.lib.' + m.name)\n"
            "print(len(list(pkgutil.iter_modules(L.__path__))))\n"
            "print(sorted(k for k in sys.modules if k.split('.')[0] in ('cosim', 'orchestrator',"
            " 'zenoh') or (k.startswith('nodes.') and k != 'nodes.fatigue'"
            " and not k.startswith('nodes.fatigue.lib'))))\n")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    n, loaded = r.stdout.split("\n")[:2]
    assert int(n) > 15 and loaded == "[]", r.stdout
