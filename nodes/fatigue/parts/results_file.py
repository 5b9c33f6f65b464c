"""A part's solved unit-load results, shipped beside its part file (``PART.influence.npz``).

Solving the CAD arm takes minutes (gmsh, the P2 solve of every unit case); a fatigue run needs
the results in a second. So a part file ``lower_arm.toml`` may have ``lower_arm.influence.npz``
beside it, written by ``suscosim part solve lower_arm.toml``; :func:`part_results` takes it when
its ``key`` is the part's own (:func:`nodes.fatigue.parts.build.part_key`: the part file's
parsed content and its geometry's bytes, the mesh sizes, the FE code's version) and otherwise
solves (and caches). A results file for another version of the part is never used.

The file (NumPy ``.npz``, compressed, no pickles; docs/parts.md, "Shipped results"):
``format`` ``"suscosim-part-results"``, ``version`` 1, ``key`` (16 hex digits), ``part`` (its
name), ``case_names`` (JSON), ``coefficients`` (cases, nodes, 6) [Pa per N or N m] (Voigt
xx, yy, zz, xy, yz, zx) of the assessed surface nodes, ``node_xyz`` (nodes, 3) [m],
``node_ids``, ``surface`` and ``meta`` (JSON: mass, modes, mesh, assessment rule; the part as
:func:`.build.part_names` names it: its file's name beside this file, SHA-256, geometry).
A damaged or foreign file is an `InputFileError` naming it, never a silent re-solve.
"""

from __future__ import annotations

import os
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from cosim.errors import InputFileError

from ..lib.influence_set import InfluenceSet
from .build import from_npz, part_influence, part_key, part_names, save_npz
from .schema import Part

FORMAT = "suscosim-part-results"
VERSION = 1
SUFFIX = ".influence.npz"


def results_path(part: Part) -> Path:
    """Where a part's shipped results live: beside its part file, ``<stem>.influence.npz``."""
    return part.path.with_name(part.path.stem + SUFFIX)


def current_key(part: Part, mesh_size: float | None = None) -> str:
    """The key of the part's results at ``mesh_size`` (default: the part file's recipe)."""
    size = part.mesh_size if mesh_size is None else float(mesh_size)
    return part_key(part, size, part.fillet_size * size / part.mesh_size)


def write_results(part: Part, inf: InfluenceSet, key: str, path: Path | None = None) -> Path:
    """Write ``inf`` as the part's results file (aside, then renamed into place)."""
    path = results_path(part) if path is None else path
    meta = {**inf.meta, **part_names(part),  # the part file relative to this file
            "part": Path(os.path.relpath(part.path.resolve(), path.resolve().parent)).as_posix()}
    save_npz(path, inf, meta, compressed=True, format=FORMAT, version=VERSION, key=key,
             part=part.name)
    return path


def read_results(path: Path) -> tuple[str, InfluenceSet]:
    """A results file's key and influence set; a damaged or foreign file is an
    `InputFileError` that names what is wrong."""
    try:
        with np.load(path, allow_pickle=False) as z:
            if "format" not in z.files or str(z["format"]) != FORMAT:
                raise InputFileError(str(path), f"not a {FORMAT} file (no 'format' entry)")
            if int(z["version"]) != VERSION:
                raise InputFileError(str(path), f"{FORMAT} version {int(z['version'])}: this "
                                           f"suscosim reads version {VERSION}")
            key, inf = str(z["key"]), from_npz(z)
    except InputFileError:
        raise
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise InputFileError(str(path), f"unreadable part results ({exc})") from None
    n = inf.coefficients.shape
    if (inf.coefficients.ndim != 3 or n[0] != len(inf.case_names) or n[2] != 6
            or inf.node_xyz is None or inf.node_xyz.shape != (n[1], 3)
            or inf.node_ids.shape != (n[1],) or inf.surface.shape != (n[1],)):
        raise InputFileError(str(path), f"inconsistent arrays: coefficients {n}, "
                                   f"{len(inf.case_names)} case names")
    if not np.all(np.isfinite(inf.coefficients)):
        raise InputFileError(str(path), "coefficients with NaN or infinite values")
    return key, inf


def part_results(part: Part, mesh_size: float | None = None,
                 log: Callable[[str], None] | None = None) -> InfluenceSet:
    """The part's influence set: its shipped results file when it is for this very part
    (same key), else solved (and cached) by `part_influence`; ``log`` says which."""
    path = results_path(part)
    key = current_key(part, mesh_size)
    inf = None
    if path.is_file():
        got, inf = read_results(path)
        if got != key:
            inf = None
            if log is not None:
                log(f"{path.name} is for another version of {part.name} (key {got}, the "
                    f"part's is {key}): solving the part (minutes; `suscosim part solve` "
                    "ships it)")
    if inf is None:
        inf = part_influence(part, mesh_size)
    # a file or cache from before the portable names: the part named as now (same key:
    # the same part file content and geometry)
    inf.meta = {**inf.meta, **part_names(part)}
    return inf
