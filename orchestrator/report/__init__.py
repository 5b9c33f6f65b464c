"""``suscosim report RUN_OR_SWEEP_DIR``: a self-contained HTML page of a run or a sweep. No
server, network or JavaScript: matplotlib PNGs as ``data:`` URIs, inline CSS, relative links
(docs/report.md). A failed run renders too, every missing piece named with the command that
makes it. Exit codes: 0 written, 2 bad input.
"""

from __future__ import annotations

from .cli import build_parser, main, render
from .sweep_data import Point, law_axis, vs_passive

__all__ = ["Point", "build_parser", "law_axis", "main", "render", "vs_passive"]
