"""ANSYS ``PRNSOL,S,COMP`` listings (a unit-load case's nodal stresses) read, or refused
naming the format expected.

The listing ANSYS Mechanical APDL prints with ``PRNSOL,S,COMP`` (``/OUTPUT`` to a file):
page headers (``PRINT S NODAL SOLUTION PER NODE``, ``LOAD STEP=...``, ``THE FOLLOWING X,Y,Z
VALUES ARE IN GLOBAL COORDINATES``), a column line ``NODE SX SY SZ SXY SYZ SXZ`` before each
page's data, rows of the node number and the six components (whitespace separated, in the
listing's stress unit), and at the end the ``MINIMUM VALUES`` / ``MAXIMUM VALUES`` block
(``NODE`` and ``VALUE`` rows), which is skipped. Other column sets (``PRNSOL,S,PRIN``:
S1 S2 S3 SINT SEQV) cannot give the six components superposition needs and are refused.

Returns what :func:`influence.read_case_csv` returns: (node ids, None, stresses (n, 6) in the
file's unit; SXZ is Szx).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from cosim.errors import InputFileError
from cosim.safe_open import open_user_file

COLUMNS = ("NODE", "SX", "SY", "SZ", "SXY", "SYZ", "SXZ")
EXPECTED = ("an ANSYS PRNSOL,S,COMP listing: a column line 'NODE SX SY SZ SXY SYZ SXZ' and "
            "rows of a node number and six stresses")
_NUM = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([EeDd][-+]?\d+)?$")


def looks_like_prnsol(path: Path) -> bool:
    """Whether the first 60 lines (64 kB at most) of ``path`` have a PRNSOL header or column
    line; an InputFileError when ``path`` is not a regular file (:mod:`cosim.safe_open`)."""
    with open_user_file(path, "influence", "fatigue.mapping") as fh:
        head = fh.read(1 << 16).decode("utf-8", errors="replace").splitlines()[:60]
    text = " ".join(head).upper()
    return ("NODAL SOLUTION PER NODE" in text or "POST1 NODAL STRESS LISTING" in text
            or bool(re.search(r"\bNODE\s+SX\s+SY\s+SZ\b", text)))


def read_prnsol(path: Path) -> tuple[np.ndarray, None, np.ndarray]:
    """(node ids, None, stresses (n, 6)) of a PRNSOL,S,COMP listing; InputFileError naming
    the file, the line and `EXPECTED` otherwise."""
    p = str(path)
    ids: list[int] = []
    rows: list[list[float]] = []
    in_data = False
    seen_cols = False
    with open_user_file(path, "influence", "fatigue.mapping") as raw:
        fh = (b.decode("utf-8", errors="replace") for b in raw)
        for lineno, line in enumerate(fh, start=1):
            cells = line.split()
            if not cells:
                continue
            up = [c.upper() for c in cells]
            if up[0] in ("NODE", "VALUE") and len(up) > 1 and _NUM.match(cells[1]):
                in_data = False  # the MINIMUM / MAXIMUM block: NODE n..., VALUE v...
                continue
            if up[0] == "NODE" and len(up) > 1:
                if tuple(up) != COLUMNS:
                    raise InputFileError(p, f"columns {' '.join(cells)}: expected {EXPECTED}",
                                         lineno)
                in_data = seen_cols = True
                continue
            if up[0] in ("MINIMUM", "MAXIMUM"):
                in_data = False  # the summary block at the end
                continue
            if not in_data:
                continue
            if all(_NUM.match(c) for c in cells):
                if len(cells) != 7:
                    raise InputFileError(p, f"expected 7 numbers (node + 6 stresses), got "
                                            f"{len(cells)}", lineno)
                vals = [float(c.replace("D", "E").replace("d", "e")) for c in cells]
                if not np.all(np.isfinite(vals)):
                    raise InputFileError(p, "non-finite value", lineno)
                ids.append(int(vals[0]))
                rows.append(vals[1:])
            else:
                in_data = False  # a page header between pages
    if not seen_cols or not rows:
        raise InputFileError(p, f"no nodal stresses: expected {EXPECTED}")
    a = np.asarray(ids, dtype=np.int64)
    if np.unique(a).size != a.size:
        raise InputFileError(p, "a node is listed twice")
    return a, None, np.asarray(rows)
