"""The built-in arm's mesh-convergence table (#26 item 2), logged mesh by mesh.

    python bench/arm_convergence.py [OUT.json]

The same computation as ``suscosim part check nodes/fatigue/parts/data/lower_arm.toml
--convergence`` (``card.convergence`` with the part file's ``mesh.convergence``,
``convergence_local`` and ``convergence_radius``, the plant's static loads) without the card's
own mesh and six modes; prints a line per mesh as it is solved and the table as JSON (to OUT,
written aside and renamed, and to stdout).
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from nodes.fatigue.parts.card import convergence  # noqa: E402
from nodes.fatigue.parts.data import __file__ as _data  # noqa: E402
from nodes.fatigue.parts.schema import load_part  # noqa: E402
from orchestrator.studies.arm_card import static_arm_loads  # noqa: E402


def main() -> None:
    part = load_part(Path(_data).parent / "lower_arm.toml")
    loads = {k: v for k, v in static_arm_loads().items() if k in part.channels}
    cv = convergence(part, part.convergence, loads, log=lambda s: print(s, flush=True))
    text = json.dumps(cv, indent=2)
    if len(sys.argv) > 1:
        out = Path(sys.argv[1])
        tmp = out.with_name(out.name + f".{os.getpid()}.tmp")
        tmp.write_text(text)
        os.replace(tmp, out)
    print(text)


if __name__ == "__main__":
    main()
