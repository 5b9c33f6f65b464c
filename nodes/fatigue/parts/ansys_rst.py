"""ANSYS Mechanical APDL result files (``.rst``) of unit-load cases as an `InfluenceSet`.

Each result set of the file (load step / substep, in the file's order) is one unit case,
named by ``case_names``. The stresses are the reader's (``ansys-mapdl-reader``) nodal
stresses: the element nodal stresses in the global Cartesian system, averaged over the
elements that share a node (MAPDL's ``PRNSOL,S`` with ``AVPRIN,0``).

* **Component order.** The reader gives ``X, Y, Z, XY, YZ, XZ``; the project's order
  (`InfluenceSet`, as CalculiX's ``SXX SYY SZZ SXY SYZ SZX``) is ``xx, yy, zz, xy, yz, zx``.
  The stress tensor is symmetric, so ``XZ`` is ``zx`` and the columns map one to one
  (`RST_TO_VOIGT`); tests/fatigue/test_part_ansys.py checks it against the reader's
  principal stresses, which depend on which shear sits where.
* **Nodes.** MAPDL writes element nodal stresses at the corner nodes only: the midside nodes
  of quadratic elements (and nodes of elements with no stress output: masses, surface
  effect elements, or nodes outside the solved selection) have no stress (NaN from the
  reader). They are **dropped**; a node with stress in one case and none in another is
  dropped too; the counts are in ``meta``. Shell elements are refused (the reader's nodal
  stress does not separate their top and bottom layers).
* **Surface.** ``surface`` flags the nodes on the free faces of the solid elements (the
  mesh's exterior, from the file's element topology), as the built-in arm's set does; the
  fatigue worker assesses those by default (``nodes = "surface"``). The joint zones are not
  known to a results file: select them out with `InfluenceSet.subset` if needed.
  (`frd_influence` flags every node: it reads no element topology.)
* **Units.** A MAPDL file carries no unit system. ``length_unit`` ("m" or "mm") scales the
  node coordinates to m; ``stress_scale`` multiplies the stresses to Pa per unit load (1e6
  for MPa per N, 1e-3 for Pa under a 1 kN load case, ...).

The reader's compiled code aborts the process on some damaged files (a truncated or
overwritten record: ``std::bad_alloc``, segmentation fault), so the file is read in a child
Python process; its death, like every other unreadable file, is an `InputFileError` naming
the file. ``ansys-mapdl-reader`` (with pyvista and vtk) is imported only there.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from cosim.errors import InputFileError
from cosim.safe_open import check_user_file, open_user_file

from ..lib.influence_set import InfluenceSet, short_channel

RST_TO_VOIGT = (0, 1, 2, 3, 4, 5)
"""Columns of the reader's (X, Y, Z, XY, YZ, XZ) taken for (xx, yy, zz, xy, yz, zx): the same
places, since XZ = ZX (symmetric tensor). Written out so that the mapping is explicit."""

LENGTH_UNITS = {"m": 1.0, "mm": 1e-3}
ANALYSIS_TYPES = {0: "static", 1: "buckling", 2: "modal", 3: "harmonic", 4: "transient",
                  7: "substructure", 8: "spectrum"}
"""MAPDL's ANTYPE codes (the result header's ``kan``)."""
SHELL_TYPES = frozenset({28, 41, 43, 57, 63, 91, 93, 99, 131, 132, 143, 150, 157, 163, 181,
                         190, 208, 209, 281})
"""MAPDL shell element routines: refused (top/bottom layers mixed by the nodal average)."""
PIP_HINT = "pip install ansys-mapdl-reader"

_CHILD = r"""
import sys, warnings
warnings.simplefilter("ignore")
import numpy as np
SOLID_VTK = (10, 11, 12, 13, 14, 24, 25, 26, 27)  # VTK's 3D cell types, linear and quadratic
try:
    from ansys.mapdl.reader import read_binary
    from ansys.mapdl.reader.rst import Result
    r = read_binary(sys.argv[1])
    if type(r) is not Result:
        raise ValueError(f"a {type(r).__name__}, not a plain (non-cyclic, non-distributed) "
                         "MAPDL result file")
    if not r.available_results["ENS"]:
        raise ValueError("no nodal stresses (ENS) in the file: solve with OUTRES,STRS")
    nnum = np.asarray(r.mesh.nnum)
    stress = []
    for i in range(r.nsets):
        ids, s = r.nodal_stress(i)
        if not np.array_equal(np.asarray(ids), nnum):
            raise ValueError(f"result set {i + 1}: its nodes are not the geometry's")
        stress.append(np.asarray(s, dtype=float))
    g = r.grid
    solid = np.flatnonzero(np.isin(np.asarray(g.celltypes), SOLID_VTK))
    surf = np.zeros(0, dtype=np.int64)
    if solid.size:
        sub = g.extract_cells(solid)
        sf = sub.extract_surface(pass_pointid=True, nonlinear_subdivision=0)
        surf = np.asarray(sub.point_data["ansys_node_num"])[
            np.asarray(sf.point_data["vtkOriginalPointIds"])]
    np.savez(sys.argv[2], nnum=nnum, xyz=np.asarray(r.mesh.nodes, dtype=float)[:, :3],
             stress=np.stack(stress), surface_nodes=np.unique(surf),
             etypes=np.unique(np.asarray(r.mesh.etype)),
             time_values=np.asarray(r.time_values, dtype=float))
except Exception as exc:
    print(f"{type(exc).__name__}: {exc}".splitlines()[0][:300], file=sys.stderr)
    sys.exit(3)
"""


def rst_header(path: Path) -> dict[str, int]:
    """The few result-header items checked before the reader sees the file: analysis type
    (``kan``), number of result sets, and where the file must end (bytes). Pure Python: a
    file that is not an MAPDL binary or is cut short is an `InputFileError` here."""
    src = str(path)
    try:
        size = check_user_file(path, "mesh", "part results (.rst)")
        with open_user_file(path, "mesh", "part results (.rst)") as fh:
            head = fh.read(4 * (105 + 80))
    except OSError as exc:
        raise InputFileError(src, f"cannot read it ({exc.strerror or exc})") from None
    order = next((e for e in "<>" if len(head) >= 4
                  and int(np.frombuffer(head[:4], f"{e}i4")[0]) == 100), None)
    if order is None:
        raise InputFileError(src, "not an ANSYS binary file (no 100-word standard header)")
    if len(head) < 4 * (105 + 80):
        raise InputFileError(src, f"truncated: {size} bytes, shorter than the result header")
    n = int(np.frombuffer(head[4 * 103:4 * 104], f"{order}i4")[0])
    if not 10 <= n <= 80:
        raise InputFileError(src, "not an ANSYS result file (no result header at word 103)")
    h = np.frombuffer(head[4 * 105:4 * (105 + n)], f"{order}i4").astype(np.int64)
    end8 = (int(h[23]) << 32) | (int(h[22]) & 0xFFFFFFFF) if n > 23 else 0
    end = 4 * (end8 if end8 > 0 else int(h[9]))
    if size < end:
        raise InputFileError(src, f"truncated: the header says the file runs to {end} bytes, "
                                  f"it has {size}")
    return {"kan": int(h[7]), "nsets": int(h[8]), "end_bytes": end, "size": size}


def read_rst(path: Path, timeout: float = 600.0) -> dict[str, np.ndarray]:
    """Every result set's nodal stress of an MAPDL ``.rst``, read by ``ansys-mapdl-reader``
    in a child process: ``nnum`` (n,), ``xyz`` (n, 3) in the file's length unit, ``stress``
    (sets, n, 6) X Y Z XY YZ XZ in the file's stress unit (NaN where a node has none),
    ``surface_nodes`` (node numbers on the solid elements' free faces), ``etypes``,
    ``time_values``."""
    try:  # looked up, not imported (vtk: about a second)
        found = importlib.util.find_spec("ansys.mapdl.reader") is not None
    except ModuleNotFoundError:  # no ``ansys`` / ``ansys.mapdl`` namespace at all
        found = False
    if not found:
        raise ModuleNotFoundError(f"reading ANSYS .rst files needs ansys-mapdl-reader: "
                                  f"{PIP_HINT}")
    return read_in_child(_CHILD, Path(path), timeout, "MAPDL result file", "the MAPDL reader")


def case_channels(case_names: Sequence[str], length_unit: str) -> list[str]:
    """The unit cases' channel names of an imported result file (:func:`short_channel`),
    after checking the arguments every importer takes: ValueError for a ``length_unit`` not
    in :data:`LENGTH_UNITS` or a case name given twice."""
    if length_unit not in LENGTH_UNITS:
        raise ValueError(f"length_unit must be one of {tuple(LENGTH_UNITS)}, got "
                         f"{length_unit!r}")
    names = [short_channel(c) for c in case_names]
    if len(set(names)) != len(names):
        raise ValueError(f"case names repeat: {list(case_names)}")
    return names


def read_in_child(code: str, path: Path, timeout: float, kind: str, reader: str
                  ) -> dict[str, np.ndarray]:
    """The arrays the Python ``code`` saves (``np.savez(sys.argv[2], ...)``) from the file
    ``path`` (``sys.argv[1]``), run in a child process; its exit code 3 with a one-line
    message on stderr, its death or its timeout is an `InputFileError` naming the file
    ("not a readable ``kind`` (...)")."""
    src = str(path)
    with tempfile.TemporaryDirectory(prefix="suscosim-read-") as tmp:
        out = Path(tmp) / "out.npz"
        try:
            r = subprocess.run([sys.executable, "-c", code, str(Path(path).resolve()),
                                str(out)], capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            raise InputFileError(src, f"{reader} took over {timeout:.0f} s") from None
        if r.returncode != 0 or not out.is_file():
            msg = r.stderr.strip().splitlines()
            how = (f"killed by signal {-r.returncode}" if r.returncode < 0
                   else f"exit code {r.returncode}")
            why = (msg[-1] if msg else "no message") if r.returncode == 3 else (
                f"{reader} died, {how}{': ' + msg[-1].strip() if msg else ''}; "
                f"a damaged file?")
            raise InputFileError(src, f"not a readable {kind} ({why})")
        with np.load(out, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}


def rst_influence(path: Path, case_names: Sequence[str], stress_scale: float = 1.0,
                  length_unit: str = "m", static_only: bool = True) -> InfluenceSet:
    """Unit-case stresses from an MAPDL ``.rst`` (one result set per case, in order) as an
    `InfluenceSet` in Pa per unit load (``stress_scale`` converts the file's unit, e.g. 1e6
    for MPa; ``length_unit`` "m" or "mm" is the unit of the node coordinates).

    Nodes without a stress (midside nodes, nodes of elements with no stress output) are
    dropped; ``surface`` flags the nodes on the solid mesh's free faces. ``static_only``
    refuses a file of another analysis type (a modal file's result sets are mode shapes,
    not unit loads); ``False`` reads its sets as cases all the same. Module docstring:
    component order, units, why the reader runs in a child process.
    """
    src = str(path)
    names = case_channels(case_names, length_unit)
    hdr = rst_header(Path(path))
    analysis = ANALYSIS_TYPES.get(hdr["kan"], f"ANTYPE {hdr['kan']}")
    if static_only and hdr["kan"] != 0:
        raise InputFileError(src, f"a {analysis} analysis ({hdr['nsets']} result sets): unit-"
                                  f"load cases are static load steps (ANTYPE,STATIC); "
                                  f"static_only=False reads its sets as cases all the same")
    if hdr["nsets"] != len(names):
        raise InputFileError(src, f"{hdr['nsets']} result sets for {len(names)} load cases "
                                  f"({', '.join(names)})")
    d = read_rst(Path(path))
    shells = sorted(int(t) for t in d["etypes"] if int(t) in SHELL_TYPES)
    if shells:
        raise InputFileError(src, f"shell elements ({', '.join(f'type {t}' for t in shells)}):"
                                  f" their nodal stress mixes top and bottom layers; "
                                  f"only solid-element results are read")
    stress = d["stress"][:, :, RST_TO_VOIGT]  # (sets, nodes, 6): xx yy zz xy yz zx
    has = np.isfinite(stress).all(axis=2)  # (sets, nodes)
    keep = has.all(axis=0)
    partial = int((has.any(axis=0) & ~keep).sum())
    if not keep.any():
        raise InputFileError(src, "no node has a stress in every result set")
    ids = d["nnum"][keep].astype(np.int64)
    coef = np.ascontiguousarray(stress[:, keep]) * stress_scale
    xyz = d["xyz"][keep] * LENGTH_UNITS[length_unit]
    surface = np.isin(ids, d["surface_nodes"])
    meta = {
        "source": "ansys-rst", "file": src, "analysis": analysis,
        "time_values": [float(t) for t in d["time_values"]],
        "element_types": [int(t) for t in d["etypes"]],
        "stress_scale": float(stress_scale), "length_unit": length_unit,
        "n_nodes_in_file": int(d["nnum"].size), "n_nodes": int(ids.size),
        "n_nodes_dropped_no_stress": int(d["nnum"].size - keep.sum()),
        "n_nodes_dropped_stress_in_some_sets_only": partial,
        "n_surface_nodes": int(surface.sum()),
        "surface_rule": "nodes on the free faces of the solid elements",
    }
    return InfluenceSet(names, coef, xyz, ids, surface, meta)
