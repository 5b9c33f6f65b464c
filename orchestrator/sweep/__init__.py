"""``suscosim sweep SWEEP.toml``: a grid of scenarios, several runs at once, resumable.

    suscosim sweep SWEEP.toml [--out DIR] [--jobs N] [--connect EP] [--external NODE]
                              [--no-fatigue] [--list]
    suscosim sweep SWEEP.toml --serve NODE --connect EP     (on another machine)
    suscosim sweep SWEEP.toml --executor dask --scheduler tcp://HOST:8786

``--executor dask`` runs every point whole on a worker of a Dask cluster
(:mod:`orchestrator.sweep.dask_exec`, :mod:`orchestrator.sweep.task`); ``[sweep.design]``
samples parameter ranges (:mod:`orchestrator.sweep.design`) and adds a sensitivity table
(:mod:`orchestrator.sweep.sensitivity`); ``[sweep] fork_at = T`` runs one parent per group
of points that differ only in what a fork may change (the controller) and every point as a
fork of it at T (:mod:`orchestrator.sweep.fork`: each law then acts from T on). docs/sweeps.md
has all of it.

A sweep file names a base scenario and a grid; every grid point is one run::

    [sweep]
    name = "ch6_pave"                    # default: the file's stem
    base = "../ch4_qvm_realistic_pave.toml"   # relative to the sweep file; a list = an axis
    jobs = 2                             # runs at once (default: cores // 2, at least 1)
    fatigue = true                       # fatigue worker on each finished run (default false)
    channels = ["plant/response/a_b"]    # channels in the results table (default: a few)
    [sweep.grid]                         # the axes; the points are their product
    "road.speed_kmh" = [30, 50]          # a dotted scenario key and its values
    [sweep.grid.strategy]                # an axis of named variants, each a set of overrides
    passive = { controller = { law = "passive", c = 3800.0, velocity = "damper" } }
    tss1 = { controller = { law = "tss1", preset = "realistic", velocity = "damper" } }
    [sweep.set]                          # fixed overrides for every point
    "run.h" = 0.001

Override keys are the dotted keys of ``suscosim run --set`` (quote them in TOML, or TOML
reads ``road.speed_kmh`` as a nested table); a table value replaces the whole table at its
key (``controller = {...}`` replaces the base's controller section). Relative file paths in
overrides (``road.path``, ``controller.curve``, ``fatigue.influence``) are relative to the
sweep file's folder.

Each point is ``suscosim run BASE --set ... --set run.id=<point id> --out DIR/runs/<point id>
--quiet`` in its own process group (a crashed run cannot take the sweep down), as many at
once as ``--jobs``. Its id is the sweep name and the point's values, so a restart finds it.

Sweep folder (``--out``, default ``sweeps/<name>``)::

    sweep.json      {"name", "base", "grid", "set", "points": [{"id", "params", "run_dir"}]}
    runs/<id>/      a run folder (+ point.json, sweep.log; fatigue/ when fatigue is on)
    results.csv     one row per point: id, params, status, error, timing, peaks/RMS, fatigue
    results.json    the same rows as a JSON list

Resumable: a point whose run folder holds ``summary.json`` with status ok (and
``fatigue/summary.json`` when fatigue is on) for the same resolved scenario is not redone;
a failed or unfinished one is; an ok run whose fatigue is missing gets only its fatigue.

Exit codes: 0 every point ok, 1 a point failed, 2 bad sweep file (nothing was started),
130 interrupted.
"""

from __future__ import annotations

import sys

from .cli import build_parser, main
from .display import Display
from .local import Job, Runner
from .procs import ROOT
from .results import result_rows, results_table, write_results, write_sweep_json
from .serve import serve
from .spec import (
    DEFAULT_CHANNELS,
    FATIGUE_COLUMNS,
    MAX_ID,
    RESERVED,
    SWEEP_KEYS,
    Axis,
    Point,
    Sweep,
    SweepError,
    load_sweep,
    point_id,
    toml_value,
    validate_points,
)
from .state import point_state

__all__ = ["DEFAULT_CHANNELS", "FATIGUE_COLUMNS", "MAX_ID", "RESERVED", "ROOT", "SWEEP_KEYS",
           "Axis", "Display", "Job", "Point", "Runner", "Sweep", "SweepError", "build_parser",
           "load_sweep", "main", "point_id", "point_state", "result_rows",
           "results_table", "serve", "toml_value", "validate_points", "write_results",
           "write_sweep_json"]

if __name__ == "__main__":
    sys.exit(main())
