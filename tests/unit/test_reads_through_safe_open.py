"""#46 item 1: no reader opens a file a user names by itself. A scan of cosim/, nodes/ and
orchestrator/ finds every ``open(``, ``.read_bytes(`` and ``.read_text(`` that reads; each
must be in the allow-list below (a file the program wrote or ships, /proc, or a file of a
handed run folder still read directly, each with its reason). A new read of a user's path
fails here: it goes through :mod:`cosim.safe_open` (regular file, bounded)."""

from __future__ import annotations

import re

from tests.conftest import ROOT

READ = re.compile(r"\bopen\(|\.read_bytes\(|\.read_text\(")
NOT_A_READ = re.compile(
    r"os\.open\(.*O_(WRONLY|RDWR)|open\([^)]*[\"'](w|wb|a|ab|x)[\"']|zenoh\.open|webbrowser\."
    r"open|tarfile\.open|def _?open|\._open\(|part\.open\(|\.open\(self|os\.open\(os\.devnull|"
    r"os\.open\((path\.parent|self\.path)|safe_open|crg\.open")

ALLOWED: dict[str, dict[str, str]] = {
    # file -> {text of the line: why it is not a user's file read unbounded}
    "cosim/safe_open.py": {"os.open(path, flags)": "the one opening function"},
    "cosim/auth.py": {"p.read_bytes().strip()": "the run key file (#43: its own checks)"},
    "cosim/run_folder.py": {"Path(path).read_text()": "a run folder's status (JSON it wrote)",
                            "/proc/{pid}/stat": "/proc"},
    "cosim/formats/stream.py": {"open(src, newline=\"\")": "a run's table.csv (export)"},
    "cosim/checkpoint.py": {"read_text()": "a checkpoint manifest (#43's plain data)",
                            "path.read_bytes()": "a checkpoint file (#43: size, MAC)"},
    "cosim/table.py": {"open(path, newline=\"\")": "a run's table.csv",
                       "open(csv_path, \"rb\")": "a run's table.csv (row count)"},
    "cosim/journal.py": {"open(self.path, \"rb\")": "a journal: read in 1 MiB windows",
                         "open(reader.path, \"rb\")": "a journal's tail"},
    "nodes/fatigue/parts/cad_arm.py": {"open(path, \"rb\")": "the shipped CAD parameters"},
    "nodes/fatigue/parts/schema.py": {"DEFAULT_PARAMS.read_text()": "shipped parameters",
                                      "gp.read_bytes()": "a part's geometry, for its digest"},
    "nodes/fatigue/parts/calculix.py": {"read_text(errors=\"replace\")": "CalculiX's output"},
    "nodes/fatigue/parts/build.py": {"part.path.read_bytes()": "a part file already loaded"},
    "nodes/fatigue/materials/__init__.py": {"path.read_text()": "the shipped material library"},
    "nodes/plant/model.py": {"path.read_bytes()": "the .bullet file PyBullet just wrote"},
    "orchestrator/fmu_slave.py": {"read_text()": "the exported FMU's own resources"},
    "orchestrator/compose_gen.py": {"read_text()": "the repository's compose templates"},
    "orchestrator/sweep/phases.py": {"log.read_text(": "a sweep point's log it wrote"},
    "orchestrator/scope/server.py": {"(STATIC / name).read_bytes()": "shipped static files"},
    "orchestrator/export_fmu.py": {"SLAVE_TEMPLATE.read_text()": "a shipped template"},
    "orchestrator/report/markup.py": {"joinpath(\"report.css\").read_text(": "the shipped CSS"},
    "orchestrator/placement.py": {"/proc/{pid}/task": "/proc"},
    "orchestrator/local_mesh.py": {"OWNER_FILE).read_text()": "the mesh folder it made"},
    "orchestrator/ride.py": {"read_text()": "a run folder's scenario.json"},
    "orchestrator/tap/stats.py": {"open(self.path, newline=\"\")": "the CSV it appends to"},
}


def test_every_read_is_through_safe_open_or_allowed() -> None:
    unexpected = []
    for folder in ("cosim", "nodes", "orchestrator"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            rel = str(path.relative_to(ROOT))
            allowed = ALLOWED.get(rel, {})
            for i, line in enumerate(path.read_text().splitlines(), start=1):
                code = line.split("#", 1)[0]
                if not READ.search(code) or NOT_A_READ.search(code) or \
                        code.lstrip().startswith(('"', "'", ">>>")):
                    continue
                if not any(text in code for text in allowed):
                    unexpected.append(f"{rel}:{i}: {line.strip()}")
    assert unexpected == [], "read a user's file through cosim.safe_open:\n" + \
        "\n".join(unexpected)
