"""Where stress influence coefficients (an :class:`~nodes.fatigue.lib.influence_set.InfluenceSet`)
come from:

* the built-in arm and every part file are meshed and solved by :mod:`nodes.fatigue.parts`
  (results shipped beside the part file, else cached under `cache_dir`);
* `import_influence`: per-case CSV tables exported from a commercial FE code (thesis App V:
  one file per unit load case, one row per node, columns Sx Sy Sz Sxy Syz Szx), with the
  scenario's mapping of load channels to files (and a scale/sign per channel, for axis
  conventions that differ between the MBS and FE codes).
"""

from __future__ import annotations

import csv
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from cosim.errors import InputFileError
from cosim.safe_open import open_user_text

from .lib.influence_set import InfluenceSet, short_channel
from .prnsol import looks_like_prnsol, read_prnsol


# ------------------------------------------------------------------------------- cache
def cache_dir() -> Path:
    """Where FE results are cached: $SUSCOSIM_CACHE or ~/.cache/suscosim."""
    root = os.environ.get("SUSCOSIM_CACHE")
    return Path(root) if root else Path.home() / ".cache" / "suscosim"


# -------------------------------------------------------------------------------- imported
def _is_number(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


def read_case_csv(path: Path) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """Read one unit-load case table.

    Accepted layouts (comma separated; header lines that are not numbers are skipped, as the
    thesis stripped ANSYS headers): 6 columns ``Sx,Sy,Sz,Sxy,Syz,Szx``; 7 columns
    ``node,Sx..Szx``; 10 columns ``node,x,y,z,Sx..Szx``.

    Returns (node_ids, xyz or None, stresses (n, 6)).
    """
    p = str(path)
    rows: list[list[float]] = []
    ncol = None
    with open_user_text(path, "influence", "fatigue.mapping") as fh:
        for lineno, row in enumerate(csv.reader(fh), start=1):
            cells = [c.strip() for c in row if c.strip() != ""]
            if not cells:
                continue
            if not all(_is_number(c) for c in cells):
                if rows:
                    raise InputFileError(p, f"non-numeric value in {cells}", lineno)
                continue  # header
            if ncol is None:
                ncol = len(cells)
                if ncol not in (6, 7, 10):
                    raise InputFileError(
                        p, f"expected 6, 7 or 10 columns (Sx..Szx, node+6, node+xyz+6), "
                           f"got {ncol}", lineno)
            elif len(cells) != ncol:
                raise InputFileError(p, f"expected {ncol} columns, got {len(cells)}", lineno)
            vals = [float(c) for c in cells]
            if not np.all(np.isfinite(vals)):
                raise InputFileError(p, "non-finite value", lineno)
            rows.append(vals)
    if not rows:
        raise InputFileError(p, "no numeric rows")
    a = np.asarray(rows)
    if ncol == 6:
        return np.arange(1, a.shape[0] + 1), None, a
    if ncol == 7:
        return a[:, 0].astype(np.int64), None, a[:, 1:]
    return a[:, 0].astype(np.int64), a[:, 1:4], a[:, 4:]


def import_influence(base: Path, mapping: Mapping[str, str | Mapping[str, Any]],
                     stress_scale: float = 1.0) -> InfluenceSet:
    """Influence coefficients from per-case CSV (or PRNSOL) files in the folder ``base`` (or
    ``base``'s folder): ``mapping`` load channel (full column or short) -> file name, or
    {"file": name, "scale": s}, the channel's load multiplying s times the file's stresses
    (s = -1 flips an axis); ``stress_scale`` multiplies every stress (1e6: MPa per N)."""
    base = Path(base)
    folder = base if base.is_dir() else base.parent
    names: list[str] = []
    coefs: list[np.ndarray] = []
    ids_ref = xyz_ref = None
    for channel, spec in mapping.items():
        if isinstance(spec, str):
            fname, scale = spec, 1.0
        else:
            fname, scale = spec["file"], float(spec.get("scale", 1.0))
        path = folder / fname
        ids, xyz, s = read_prnsol(path) if looks_like_prnsol(path) else read_case_csv(path)
        if ids_ref is None:
            ids_ref, xyz_ref = ids, xyz
        elif ids.shape != ids_ref.shape or not np.array_equal(ids, ids_ref):
            raise InputFileError(str(path), f"node list differs from the first case "
                                            f"({ids.size} vs {ids_ref.size} nodes)")
        names.append(short_channel(channel))
        coefs.append(s * scale * stress_scale)
    if not names:
        raise InputFileError(str(base), "no load cases in the mapping")
    assert ids_ref is not None
    return InfluenceSet(names, np.stack(coefs), xyz_ref, ids_ref,
                        np.ones(ids_ref.size, dtype=bool),
                        {"source": "imported", "folder": str(folder),
                         "mapping": {k: v for k, v in mapping.items()}})
