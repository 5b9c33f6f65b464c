"""Nastran result files (``.op2``) of unit-load cases as an `InfluenceSet`.

Each subcase of the file (ascending SUBCASE id; each time step of a subcase with several) is
one unit case, named by ``case_names``. Read by pyNastran's OP2 reader (``read_op2_geom``):

* **Stress**: the solid elements' stress tables (``OES1``/``OES1X``: CTETRA, CPENTA, CHEXA,
  CPYRAM) at the corner grid points (``STRESS(SORT1,CORNER)`` or ``BILIN``), averaged over
  the elements that share a node (as MAPDL's ``PRNSOL`` and ccx's nodal stress). The
  element-centre rows (grid 0) are not used; a file with centre output only
  (``STRESS(CENTER)``) has no nodal stress and is refused. Other elements' tables (shells,
  beams) are not read: their nodes get no stress from them.
* **Component order**: pyNastran's ``oxx oyy ozz txy tyz txz`` is ours ``xx yy zz xy yz zx``
  (``txz`` = ``zx``: symmetric tensor), column for column (`OP2_TO_VOIGT`).
* **Coordinate system**: Nastran gives solid stresses in the material system of the element
  (PSOLID ``CORDM``); only the basic system (CORDM = 0, the default) is read: a file whose
  stress rows name another system is refused (they would have to be rotated per element).
* **Nodes**: those with a corner stress in every case; a node with a stress in some cases
  only is dropped (counted in ``meta``). Coordinates from the file's GEOM1 (written with
  ``PARAM,POST,-1``), in the basic system; ``surface`` flags the nodes on the free faces of the
  solid elements of GEOM2 (a face that only one element has). A file without geometry has
  ``node_xyz`` None and every node flagged, as `frd_influence`.
* **Units**: none in the file: ``length_unit`` ("m" or "mm") scales the coordinates to m,
  ``stress_scale`` the stresses to Pa per unit load (1e6 for MPa under 1 N cases).
* **Analysis**: ``static_only`` (default) refuses a set that is not a static solution
  (pyNastran's ``analysis_code`` 1): a modal file's sets are mode shapes.

pyNastran runs in a **child Python process** (as the MAPDL reader: `read_in_child`): its
latest release, 1.4.1, declares ``numpy<2`` and calls ``np.in1d``, which numpy 2.4 removed;
the child aliases it to ``np.isin`` before importing pyNastran, so the project's own numpy is
left as it is, and any failure of the reader is an `InputFileError` naming the file.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from cosim.errors import InputFileError

from ..lib.influence_set import InfluenceSet
from .ansys_rst import LENGTH_UNITS, case_channels, read_in_child

OP2_TO_VOIGT = (0, 1, 2, 3, 4, 5)
"""Columns of pyNastran's (oxx, oyy, ozz, txy, tyz, txz) taken for (xx, yy, zz, xy, yz, zx)."""
PIP_HINT = ('pip install --no-deps "pyNastran==1.4.1" cpylog docopt-ng colorama'
            "  (its numpy<2 pin does not hold: pyproject.toml)")
STATIC = 1
"""pyNastran's ``analysis_code`` of a static solution (SOL 101)."""

FACES = {
    4: ((0, 1, 2), (0, 1, 3), (1, 2, 3), (0, 2, 3)),  # CTETRA
    5: ((0, 1, 2, 3), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)),  # CPYRAM
    6: ((0, 1, 2), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)),  # CPENTA
    8: ((0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6),
        (3, 0, 4, 7)),  # CHEXA
}
"""Corner-node faces of the solid elements by their number of corners (Nastran's order)."""

_CHILD = r"""
import sys, warnings
warnings.simplefilter("ignore")
import numpy as np
if not hasattr(np, "in1d"):  # pyNastran 1.4.1 calls np.in1d (numpy 2.4 removed it)
    np.in1d = np.isin
try:
    from pyNastran.op2.op2_geom import read_op2_geom
    m = read_op2_geom(sys.argv[1], debug=None, build_dataframe=False)
    st = m.op2_results.stress
    tables = [getattr(st, e + "_stress") for e in ("ctetra", "cpenta", "chexa", "cpyram")]
    keys = sorted({int(k) for t in tables for k in t})
    sets, out = {}, {k: [] for k in ("set", "nid", "cid", "stress")}
    codes = []
    for sc in keys:
        for t in tables:
            o = t.get(sc)
            if o is None:
                continue
            eid_cid = dict(zip(o.element_cid[:, 0].tolist(), o.element_cid[:, 1].tolist()))
            cid = np.array([eid_cid[e] for e in o.element_node[:, 0].tolist()])
            for it in range(o.data.shape[0]):
                i = sets.setdefault((sc, it), len(sets))
                if i == len(codes):
                    codes.append(int(o.analysis_code))
                out["set"].append(np.full(len(cid), i))
                out["nid"].append(o.element_node[:, 1])
                out["cid"].append(cid)
                out["stress"].append(np.asarray(o.data[it, :, :6], dtype=float))
    if not sets:
        raise ValueError("no solid-element stresses (CTETRA, CPENTA, CHEXA, CPYRAM) in the "
                         "file: ask for STRESS(SORT1,CORNER) = ALL")
    order = sorted(sets, key=lambda k: sets[k])
    gids = np.array(sorted(m.nodes), dtype=np.int64)
    xyz = np.array([m.nodes[g].get_position() for g in gids.tolist()], dtype=float)
    solid = [e for e in m.elements.values() if e.type in ("CTETRA", "CPENTA", "CHEXA", "CPYRAM")]
    ncorner = {"CTETRA": 4, "CPYRAM": 5, "CPENTA": 6, "CHEXA": 8}
    conn = np.full((len(solid), 8), -1, dtype=np.int64)
    for j, e in enumerate(solid):
        conn[j, :ncorner[e.type]] = e.node_ids[:ncorner[e.type]]
    np.savez(sys.argv[2], subcase=np.array([k[0] for k in order]),
             step=np.array([k[1] for k in order]), analysis=np.array(codes),
             set=np.concatenate(out["set"]), nid=np.concatenate(out["nid"]).astype(np.int64),
             cid=np.concatenate(out["cid"]).astype(np.int64),
             stress=np.concatenate(out["stress"]), grid=gids, xyz=xyz.reshape(-1, 3),
             el_corners=np.array([ncorner[e.type] for e in solid], dtype=np.int64), conn=conn)
except Exception as exc:
    print(f"{type(exc).__name__}: {exc}".splitlines()[0][:300], file=sys.stderr)
    sys.exit(3)
"""


def free_face_nodes(corners: np.ndarray, conn: np.ndarray) -> np.ndarray:
    """Node ids on the free faces of solid elements: ``corners`` (elements,) their number of
    corner nodes (4, 5, 6, 8), ``conn`` (elements, >= corners) their corner node ids in
    Nastran's order. A face is free when no other element has the same nodes."""
    groups: dict[int, list[np.ndarray]] = {3: [], 4: []}
    for n, faces in FACES.items():
        c = conn[corners == n]
        for f in faces:
            groups[len(f)].append(np.sort(c[:, list(f)], axis=1))
    free = [np.zeros(0, dtype=np.int64)]
    for g in groups.values():
        if g:
            faces_all, count = np.unique(np.concatenate(g), axis=0, return_counts=True)
            free.append(faces_all[count == 1].ravel())
    return np.unique(np.concatenate(free))


def nodal_average(n_sets: int, set_of: np.ndarray, nid: np.ndarray, stress: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(node ids, (sets, nodes, 6) mean of the element corner stresses at each node, (sets,
    nodes) bool: has a stress in that set) from the rows (set, node id, 6 stresses)."""
    ids, col = np.unique(nid, return_inverse=True)
    total = np.zeros((n_sets, ids.size, 6))
    count = np.zeros((n_sets, ids.size))
    np.add.at(total, (set_of, col), stress)
    np.add.at(count, (set_of, col), 1.0)
    has = count > 0
    return ids, total / np.where(has, count, 1.0)[:, :, None], has


def op2_influence(path: Path, case_names: Sequence[str], stress_scale: float = 1.0,
                  length_unit: str = "m", static_only: bool = True,
                  timeout: float = 600.0) -> InfluenceSet:
    """Unit-case stresses from a Nastran ``.op2`` (one subcase per case, ascending SUBCASE
    id) as an `InfluenceSet` in Pa per unit load (module docstring: which tables, the nodal
    average, coordinate systems, units)."""
    src = str(path)
    names = case_channels(case_names, length_unit)
    if not Path(path).is_file():
        raise InputFileError(src, "file not found")
    if importlib.util.find_spec("pyNastran") is None:
        raise ModuleNotFoundError(f"reading Nastran .op2 files needs pyNastran: {PIP_HINT}")
    d = read_in_child(_CHILD, Path(path), timeout, "Nastran OP2 file", "pyNastran")
    n_sets = int(d["subcase"].size)
    if static_only and np.any(d["analysis"] != STATIC):
        raise InputFileError(src, f"analysis codes {sorted(set(d['analysis'].tolist()))} "
                                  f"(1 is static): unit-load cases are static subcases; "
                                  f"static_only=False reads the sets as cases all the same")
    if n_sets != len(names):
        raise InputFileError(src, f"{n_sets} result sets (subcases "
                                  f"{sorted(set(d['subcase'].tolist()))}) for {len(names)} "
                                  f"load cases ({', '.join(names)})")
    corner = d["nid"] != 0
    if not corner.any():
        raise InputFileError(src, "solid stresses at the element centres only: ask for "
                                  "STRESS(SORT1,CORNER) (or BILIN) for nodal values")
    bad = np.unique(d["cid"][d["cid"] != 0])
    if bad.size:
        raise InputFileError(src, f"solid stresses in coordinate system(s) {bad.tolist()} "
                                  f"(PSOLID CORDM): only the basic system (CORDM = 0) is read")
    ids, mean, has = nodal_average(n_sets, d["set"][corner], d["nid"][corner],
                                   d["stress"][corner][:, OP2_TO_VOIGT])
    keep = has.all(axis=0)
    ids = ids[keep]
    coef = np.ascontiguousarray(mean[:, keep]) * stress_scale
    xyz = None
    surface = np.ones(ids.size, dtype=bool)
    if d["grid"].size:
        pos = np.searchsorted(d["grid"], ids)
        missing = (pos >= d["grid"].size) | (d["grid"][np.minimum(pos, d["grid"].size - 1)]
                                             != ids)
        if missing.any():
            raise InputFileError(src, f"node {int(ids[missing][0])} has a stress but no GRID "
                                      f"in the file's geometry")
        xyz = d["xyz"][pos] * LENGTH_UNITS[length_unit]
        if d["el_corners"].size:
            surface = np.isin(ids, free_face_nodes(d["el_corners"], d["conn"]))
    meta = {
        "source": "nastran-op2", "file": src, "subcases": d["subcase"].tolist(),
        "analysis_codes": d["analysis"].tolist(), "stress_scale": float(stress_scale),
        "length_unit": length_unit, "n_nodes": int(ids.size),
        "n_nodes_dropped_stress_in_some_sets_only": int((~keep).sum()),
        "n_surface_nodes": int(surface.sum()),
        "surface_rule": ("nodes on the free faces of the solid elements"
                         if d["el_corners"].size else "every node (no element topology)"),
    }
    return InfluenceSet(names, coef, xyz, ids, surface, meta)
