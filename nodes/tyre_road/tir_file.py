"""Read a tyre property file (``.tir``, the MF-Tyre / ADAMS "TeimOrbit" format).

A ``.tir`` file is sections ``[NAME]`` of ``KEY = VALUE`` lines; ``$`` and ``!`` start a
comment (to the end of the line), a string value is quoted (``'LEFT'``), a number may carry
an exponent (``2.5E-4``). Keys are case-insensitive and returned upper case, each twice: as
``KEY`` (the first one of that name: the Magic Formula's coefficients are unique across
sections) and as ``SECTION/KEY`` (``UNITS/MASS`` = 'kg' beside ``INERTIA/MASS`` = 11.0, the one
name standard files use in two sections). ``[SHAPE]`` tables (lines of bare numbers) are skipped.

Errors name the file and the line (:class:`cosim.errors.InputFileError`, exit 2).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

from cosim.errors import InputFileError
from cosim.safe_open import read_user_file

_LINE = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*=\s*(.*?)\s*$")


def _strip_comment(line: str) -> str:
    """``line`` without a ``$`` / ``!`` comment (outside quotes)."""
    quoted = False
    for i, ch in enumerate(line):
        if ch == "'":
            quoted = not quoted
        elif ch in "$!" and not quoted:
            return line[:i]
    return line


def parse_tir(text: str, source: str = "<tir>") -> dict[str, float | str]:
    """The ``KEY = VALUE`` pairs of a .tir text: numbers as ``float``, quoted strings as
    ``str`` (without the quotes). A key given twice in one section is an error (which one
    would win?)."""
    out: dict[str, float | str] = {}
    section = ""
    for n, raw in enumerate(text.splitlines(), 1):
        line = _strip_comment(raw).strip()
        if not line:
            continue
        if line.startswith("["):
            if not line.endswith("]"):
                raise InputFileError(source, f"section header without ']': {raw.strip()!r}", n)
            section = line[1:-1].strip().upper()
            continue
        m = _LINE.match(line)
        if m is None:
            if section == "SHAPE" or section.endswith("_TABLE") or line[0] in "{-+.0123456789":
                continue  # a table's rows
            raise InputFileError(source, f"expected KEY = VALUE, got {raw.strip()!r}", n)
        key, value = m.group(1).upper(), m.group(2)
        qualified = f"{section}/{key}"
        if qualified in out:
            raise InputFileError(source, f"key {key} given twice in [{section}]", n)
        parsed: float | str
        if value.startswith("'"):
            if not value.endswith("'") or len(value) < 2:
                raise InputFileError(source, f"{key}: unterminated string {value!r}", n)
            parsed = value[1:-1].strip()
        else:
            try:
                parsed = float(value)
            except ValueError:
                raise InputFileError(source, f"{key}: expected a number or a quoted string, "
                                             f"got {value!r}", n) from None
            if not math.isfinite(parsed):  # a NaN passed check and killed the run at step 0
                raise InputFileError(source, f"{key}: {value!r} is not a finite number", n)
        out[qualified] = parsed
        out.setdefault(key, parsed)
    return out


def read_tir(path: str | Path) -> dict[str, float | str]:
    """:func:`parse_tir` of the file ``path``."""
    p = Path(path)
    data = read_user_file(p, "tir", "tyre.tir")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:  # many .tir files are Latin-1 (a degree sign in a comment)
        text = data.decode("latin-1")
    return parse_tir(text, str(p))
