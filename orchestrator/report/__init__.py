"""``suscosim report RUN_OR_SWEEP_DIR``: a self-contained HTML page of a run or a sweep.

No server, network or JavaScript: matplotlib (Agg) PNGs as ``data:`` URIs, inline CSS,
relative links. docs/report.md lists the sections of a run page and a sweep page; a failed run
renders too, and every missing piece is named with the command that makes it. Exit codes: 0
written, 2 bad input (not a run or sweep folder, unreadable sweep.json, output not writable).

Modules: :mod:`.markup` (HTML and the page frame), :mod:`.plots` (figures), :mod:`.run_data`
(a run folder), :mod:`.signals` (columns, units, Welch PSDs), :mod:`.run_page`,
:mod:`.sweep_data`, :mod:`.sweep_charts`, :mod:`.sweep_page`, :mod:`.cli`.
"""

from __future__ import annotations

from .cli import build_parser, main, render
from .run_data import BadInput, RunData, is_run_dir, is_sweep_dir, load_run
from .run_page import render_run
from .sweep_data import Point, grid_keys, law_axis, load_sweep, vs_passive
from .sweep_page import render_sweep

__all__ = ["BadInput", "Point", "RunData", "build_parser", "grid_keys", "is_run_dir",
           "is_sweep_dir", "law_axis", "load_run", "load_sweep", "main", "render", "render_run",
           "render_sweep", "vs_passive"]
