"""``suscosim sweep SWEEP.toml``: a grid of scenarios, several runs at once, resumable;
docs/sweeps.md describes the sweep file, the executors and the sweep folder. Each point is
``suscosim run BASE --set ... --out DIR/runs/<point id> --quiet`` in its own process group,
``--jobs`` at once; a restart skips a point whose run (and fatigue) finished ok for the same
resolved scenario. Exit codes: 0 every point ok, 1 a point failed, 2 bad sweep file (nothing
started), 130 interrupted.
"""

from __future__ import annotations

from .cli import build_parser, main
from .spec import Point, Sweep, SweepError, load_sweep, point_id, toml_value, validate_points

__all__ = ["Point", "Sweep", "SweepError", "build_parser", "load_sweep", "main", "point_id",
           "toml_value", "validate_points"]
