"""Tetrahedral meshes of a part: gmsh from CAD (STEP or the built-in arm's parametric CAD),
meshio from a mesh file (Gmsh ``.msh``, Abaqus/CalculiX ``.inp``, Nastran ``.bdf``).

Both give a `TetMesh`: vertex coordinates [m], tetrahedra (4 vertices; a 10-node input keeps
its corner nodes: the FE puts its quadratic nodes at the straight edges' midpoints, so a
curved-edge input mesh is taken with straight edges), the input's node labels, and named node
sets. The FE (:mod:`nodes.fatigue.lib.solid`) uses quadratic tetrahedra (scikit-fem
``ElementTetP2``) on it.

gmsh meshing: a size field refines to ``fillet_size`` on the fillet faces and along the
sharp re-entrant edges (``features.py``), growing to ``size`` over 4 fillet sizes; mesh
algorithm HXT/Delaunay, optimised (``Mesh.Optimize``), deterministic on one thread.
``refine`` adds local refinement (the convergence table's meshes, ``card.convergence``):
balls (centre, radius, size) inside which the element size is ``size``, growing to the
global size over a layer of ``RAMP`` x (global size) outside; the size at a point is the
smallest any field asks.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from cosim.errors import InputFileError
from cosim.safe_open import check_user_file, open_user_file

from ..lib.solid import TetMesh, compact_mesh

MESH_SUFFIXES = {".msh": "gmsh", ".inp": "abaqus", ".bdf": "nastran", ".nas": "nastran"}
CAD_SUFFIXES = (".step", ".stp")
RAMP = 0.3
"""Transition layer outside a refinement ball, in global element sizes (1.0 on the arm's
30 mm mesh: a 30 mm layer round 16 balls of 12 mm, > 6 GB and > 8 min for the first local
mesh before it was stopped)."""

Ball = tuple[float, float, float, float, float]
"""A refinement ball: centre x, y, z [m], radius [m], element size inside [m]."""


def _inp_includes(path: Path, folder: Path, depth: int = 0) -> list[Path]:
    """The files an Abaqus ``.inp`` pulls in by ``*INCLUDE, INPUT=...`` (meshio reads them
    itself), checked first: each a plain relative path inside the mesh's ``folder``, a
    regular file within the mesh limit (:mod:`cosim.safe_open`), at most 8 levels deep."""
    found: list[Path] = []
    with open_user_file(path, "mesh", "part mesh", inside=folder) as fh:
        for raw in fh:  # the keyword and the path as meshio's Abaqus reader takes them
            line = raw.decode("utf-8", "replace")
            if line.startswith("**") or \
                    line.partition(",")[0].strip().replace("*", "").upper() != "INCLUDE":
                continue
            ref = line.split("=")[-1].strip()
            inc = path.parent / ref
            # meshio tries the path from the working directory first: it must be the same
            if not ref or Path(ref).is_absolute() or depth >= 8 or (Path(ref).exists() and (
                    os.path.realpath(ref) != os.path.realpath(inc))):
                raise InputFileError(str(path), f"*INCLUDE {ref!r:.200}: a file inside the "
                                                f"mesh's folder, by a relative path")
            check_user_file(inc, "mesh", "part mesh *INCLUDE", inside=folder)
            found += [inc, *_inp_includes(inc, folder, depth + 1)]
    return found


def read_mesh(path: Path, scale: float = 1.0) -> TetMesh:
    """A tetrahedral mesh file through meshio (tetra or tetra10 cells; other cells are
    ignored; no tetrahedra is an `InputFileError`). ``scale`` converts its lengths to m.
    Node sets: meshio's point sets (Abaqus *NSET) by name."""
    import meshio  # type: ignore[import-untyped]

    path = Path(path)
    fmt = MESH_SUFFIXES.get(path.suffix.lower())
    if fmt is None:
        raise InputFileError(str(path), f"unknown mesh type {path.suffix!r}: expected one of "
                                        f"{sorted(MESH_SUFFIXES)}")
    check_user_file(path, "mesh", "part mesh")
    includes = _inp_includes(path, path.parent) if fmt == "abaqus" else []
    try:
        m = meshio.read(str(path), file_format=fmt)
    except (Exception, SystemExit) as exc:  # meshio raises many types, or exits (#43)
        said = f": {exc or 'exit'}" if not includes else (  # never another file's content
            f" or one of the {len(includes)} files it includes ({type(exc).__name__})")
        raise InputFileError(str(path), f"meshio could not read it{said}") from None
    tets = [c.data[:, :4] for c in m.cells if c.type in ("tetra", "tetra10")]
    if not tets:
        raise InputFileError(str(path), f"no tetrahedra (cells: {[c.type for c in m.cells]})")
    t = np.vstack(tets).astype(np.int64)
    p = np.asarray(m.points, dtype=float)[:, :3] * scale
    labels = np.arange(1, p.shape[0] + 1)
    for key in ("nastran:ref", "abaqus:ref", "gmsh:node"):
        if key in m.point_data:
            labels = np.asarray(m.point_data[key]).astype(np.int64)
    sets = {str(k): np.asarray(v, dtype=np.int64) for k, v in (m.point_sets or {}).items()}
    try:
        mesh = compact_mesh(p, t, labels, sets)
    except ValueError as exc:
        raise InputFileError(str(path), str(exc)) from None
    mesh.source = str(path)
    return mesh


def floor_at(balls: np.ndarray, size: float, floor: float, x: np.ndarray) -> float:
    """The smallest element size allowed at x: ``floor`` outside the balls (k, 5), half a
    ball's size inside it, rising linearly to ``floor`` over the ball's ramp (``RAMP`` x
    ``size``)."""
    d = np.sqrt(((balls[:, :3] - x) ** 2).sum(axis=1)) - balls[:, 3]
    s = np.clip(d / (RAMP * size), 0.0, 1.0)
    inner = 0.5 * balls[:, 4]
    return float(min(floor, (inner + s * (floor - inner)).min()))


def _floor_callback(refine: Sequence[Ball], size: float, floor: float):
    balls = np.asarray(refine, dtype=float).reshape(-1, 5)
    lo = balls[:, :3] - balls[:, 3:4] - RAMP * size
    hi = balls[:, :3] + balls[:, 3:4] + RAMP * size

    def cb(dim: int, tag: int, x: float, y: float, z: float, lc: float) -> float:
        xyz = np.array([x, y, z])
        near = np.all((xyz >= lo) & (xyz <= hi), axis=1)
        if not near.any():
            return max(lc, floor)
        return max(lc, floor_at(balls[near], size, floor, xyz))
    return cb


def _mesh_current_model(size: float, fillet_size: float, fillets: list[int],
                        sharp_curves: list[int], refine: Sequence[Ball] = ()
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Mesh the current gmsh model's volumes (first order); (p, t) with gmsh's node tags."""
    import gmsh  # type: ignore[import-untyped]

    fld = gmsh.model.mesh.field
    fields = []
    if fillets or sharp_curves:
        d = fld.add("Distance")
        if fillets:
            fld.setNumbers(d, "SurfacesList", fillets)
        if sharp_curves:
            fld.setNumbers(d, "CurvesList", sharp_curves)
        fld.setNumber(d, "Sampling", 40)
        th = fld.add("Threshold")
        for k, v in (("InField", d), ("SizeMin", fillet_size), ("SizeMax", size),
                     ("DistMin", 0.25 * fillet_size), ("DistMax", 4.0 * fillet_size + size)):
            fld.setNumber(th, k, v)
        fields.append(th)
    for x, y, z, r, h in refine:
        b = fld.add("Ball")
        for k, v in (("XCenter", x), ("YCenter", y), ("ZCenter", z), ("Radius", r),
                     ("VIn", h), ("VOut", size), ("Thickness", RAMP * size)):
            fld.setNumber(b, k, float(v))
        fields.append(b)
    if len(fields) > 1:
        mn = fld.add("Min")
        fld.setNumbers(mn, "FieldsList", fields)
        fields = [mn]
    if fields:
        fld.setAsBackgroundMesh(fields[0])
    floor = 0.5 * min(fillet_size, size)  # the unrefined mesh's floor (curvature sizing)
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 12)
    if refine:
        # gmsh clamps every size to Mesh.MeshSizeMin, the curvature sizing included: lowered
        # for the balls alone, it would refine every fillet of the part (the arm: 4312 ->
        # 8866 vertices for a ball outside it). So the floor stays a field: the callback
        # raises gmsh's size (min of curvature and fields) to floor_at(x), the unrefined
        # floor outside the balls and half the ball's size inside, over the same ramp.
        gmsh.option.setNumber("Mesh.MeshSizeMin",
                              min(floor, 0.5 * min(float(b[4]) for b in refine)))
        gmsh.model.mesh.setSizeCallback(_floor_callback(refine, size, floor))
    else:
        gmsh.option.setNumber("Mesh.MeshSizeMin", floor)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0 if fields else 1)
    gmsh.option.setNumber("Mesh.Algorithm3D", 1)  # Delaunay: deterministic single-threaded
    gmsh.option.setNumber("Mesh.Optimize", 1)
    gmsh.option.setNumber("General.NumThreads", 1)
    try:
        gmsh.model.mesh.generate(3)
    finally:
        if refine:
            gmsh.model.mesh.removeSizeCallback()
    tags, xyz, _ = gmsh.model.mesh.getNodes()
    p = xyz.reshape(-1, 3)
    index = np.zeros(int(tags.max()) + 1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(tags.size)
    etypes, _, enodes = gmsh.model.mesh.getElements(3)
    t = [index[np.asarray(n, dtype=np.int64).reshape(-1, 4)]
         for et, n in zip(etypes, enodes, strict=True) if et == 4]
    if not t:
        raise ValueError("gmsh made no tetrahedra")
    return p, np.vstack(t)


def mesh_cad(step: Path | None, size: float, fillet_size: float, scale: float = 1.0,
             builtin_params: dict | None = None, refine: Sequence[Ball] = ()) -> TetMesh:
    """Mesh a STEP file (or, with ``builtin_params``, the built-in arm's parametric CAD)
    with gmsh; also finds the CAD's sharp re-entrant edges (``features.py``). ``refine``:
    local refinement balls (module docstring), in the mesh's metres."""
    import gmsh  # type: ignore[import-untyped]

    from .features import sharp_reentrant_edges

    own = not gmsh.isInitialized()
    if own:
        gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("part")
        fillets: list[int] = []
        if builtin_params is not None:
            from .cad_arm import build

            tags = build(builtin_params)
            fillets = tags["fillets"]
            source = "built-in parametric CAD (cad_arm.py)"
        else:
            assert step is not None
            if not Path(step).is_file():
                raise InputFileError(str(step), "file not found")
            try:
                gmsh.option.setString("Geometry.OCCTargetUnit", "M")
                gmsh.model.occ.importShapes(str(step))
                gmsh.model.occ.synchronize()
            except Exception as exc:
                raise InputFileError(str(step), f"gmsh could not read the STEP: {exc}") \
                    from None
            if scale != 1.0:
                ents = gmsh.model.getEntities(3)
                gmsh.model.occ.dilate(ents, 0, 0, 0, scale, scale, scale)
                gmsh.model.occ.synchronize()
            source = str(step)
        vols = [v for _, v in gmsh.model.getEntities(3)]
        if not vols:
            raise InputFileError(str(step or "CAD"), "no solid (volume) in the geometry")
        sharp = []
        for v in vols:
            sharp += sharp_reentrant_edges(v)
        p, t = _mesh_current_model(size, fillet_size, fillets, [e["curve"] for e in sharp],
                                   refine)
        mesh = compact_mesh(p, t, np.arange(1, p.shape[0] + 1), {})
        mesh.labels = np.arange(1, mesh.p.shape[0] + 1)
        mesh.sharp_edges = (np.vstack([e["points_m"] for e in sharp]) if sharp
                            else np.zeros((0, 3)))
        mesh.fillet_faces = len(fillets)
        mesh.source = source
        gmsh.model.remove()
        return mesh
    finally:
        if own:
            gmsh.finalize()
