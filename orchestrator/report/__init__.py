"""``suscosim report``: a self-contained HTML page of a run or a sweep.

    suscosim report RUN_OR_SWEEP_DIR [--out FILE.html] [--open]

The page (default ``<DIR>/report.html``) needs no server, no network and no JavaScript: the
plots are PNG images drawn with matplotlib (Agg) and embedded as ``data:`` URIs, the CSS is
inline, and every link is an anchor in the page or a relative path to a file next to it.

A **run folder** (``scenario.json``, ``summary.json``, ``table.parquet``/``table.csv``,
``journal.msgpack``, optional ``fatigue/``) gives: the scenario and the run's status, wall
time and steps per second; time histories (body/wheel displacement and acceleration,
suspension travel, tyre and damper force: whichever the table has); PSDs (Welch) of the body
acceleration and the tyre force; the RMS/peak table of every channel; ride metrics
(:mod:`nodes.recorder.ride_metrics`); the tyre and lower-arm load histories; the fatigue
results and the damage map of the arm. A failed run renders too (its error and whatever data
exists: a table rebuilt from the journal if the run left none). Every missing piece is named
in the page with the command that makes it.

A **sweep folder** (``sweep.json`` with its points, ``runs/<id>/`` run folders, optional
``results.json``/``results.csv``) gives: a results table, the minimum life of the arm per
point (and its change against the passive point of the same grid cell when the grid has
``controller.law``), overlaid PSDs and time histories of the points, the damage maps side by
side, and a section per point.

Exit codes: 0 written, 2 bad input (not a run or sweep folder, unreadable sweep.json, output
not writable).

The package, one idea per module: :mod:`.markup` (HTML primitives and the page frame),
:mod:`.plots` (matplotlib figures as ``data:`` URIs), :mod:`.run_data` (reading a run
folder), :mod:`.signals` (which columns to show, units, Welch PSDs), :mod:`.run_page` (the run's
sections), :mod:`.sweep_data` (the sweep folder as the report sees it), :mod:`.sweep_charts`
and :mod:`.sweep_page` (the sweep's page), :mod:`.cli` (the command).
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
