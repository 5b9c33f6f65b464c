"""``suscosim sweep SWEEP.toml``: a grid of scenarios, several runs at once, resumable.

docs/sweeps.md describes the sweep file (``[sweep]`` base, ``[sweep.grid]`` axes of dotted
``--set`` keys or named variants, ``[sweep.set]``, ``[sweep.design]``, ``fork_at``), the
executors and the sweep folder (sweep.json, ``runs/<id>/``, results.csv/json). Each point is
``suscosim run BASE --set ... --out DIR/runs/<point id> --quiet`` in its own process group,
``--jobs`` at once; its id is the sweep name and its values, so a restart skips a point whose
run (and fatigue, when on) finished ok for the same resolved scenario. Modules: :mod:`.spec`
(the file), :mod:`.local` (local runs), :mod:`.dask_exec`/:mod:`.task` (Dask), :mod:`.design`
and :mod:`.sensitivity` (sampled designs), :mod:`.fork` (``fork_at``), :mod:`.results`.

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
