"""CalculiX (``ccx``) on the same mesh and unit cases: ``.inp`` writer, runner, ``.frd``
reader, and the importer of ``.frd`` unit-case results into the influence form.

The check (``suscosim part check --calculix``, tests/fatigue/test_part_calculix.py): our P2
tetrahedra are written as C3D10 elements (same nodes, midside nodes at the straight edges'
midpoints), the same 3-2-1 support dofs as ``*BOUNDARY``, and each unit case's **balanced**
load (the unit load less its rigid-body inertia forces: inertia relief, done by us) as
``*CLOAD`` on every node, one ``*STEP`` per case. ccx solves and extrapolates its integration
point stresses to the nodes, averaged over the elements that share a node — independent of our
assembly, solver and stress recovery; the mass matrix that balances the load is ours.

``.frd`` stress blocks (ASCII): a ``-4  STRESS`` header, six ``-5`` component lines
(SXX SYY SZZ SXY SYZ SZX), then one ``-1`` line per node: the node number (I10 in the long
format, I5 in the short) and 6 values (E12.5).
"""

from __future__ import annotations

import shutil
import subprocess
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from cosim.errors import InputFileError

from ..lib.influence_set import InfluenceSet

CCX_EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))
"""C3D10 midside nodes 5-10: edges 1-2, 2-3, 3-1, 1-4, 2-4, 3-4 (CalculiX manual §6.2.5)."""


def c3d10_connectivity(fe) -> np.ndarray:
    """(n_elems, 10) node indices in C3D10 order from a PartFE's P2 element dofs."""
    ed = fe.sbasis.element_dofs.T  # (e, 10): 4 vertices then 6 edges (skfem order)
    xyz = fe.node_xyz
    out = np.empty_like(ed)
    out[:, :4] = ed[:, :4]
    for k, (a, b) in enumerate(CCX_EDGES):
        mid = 0.5 * (xyz[ed[:, a]] + xyz[ed[:, b]])
        d = np.stack([np.linalg.norm(xyz[ed[:, 4 + j]] - mid, axis=1) for j in range(6)])
        j = np.argmin(d, axis=0)
        if not np.allclose(d[j, np.arange(ed.shape[0])], 0.0, atol=1e-12):
            raise RuntimeError("P2 edge node not at an edge midpoint")  # pragma: no cover
        out[:, 4 + k] = ed[np.arange(ed.shape[0]), 4 + j]
    return out


def write_inp(path: Path, fe, B: np.ndarray, fixed_dofs: np.ndarray,
              case_names: Sequence[str]) -> None:
    """A CalculiX input: nodes, C3D10 elements, material, 3-2-1 boundary, one static step
    per column of B (nodal forces [N], dof order of ``fe.node_dofs``)."""
    conn = c3d10_connectivity(fe) + 1
    lines = ["*HEADING", "suscosim part check: unit cases on inertia relief", "*NODE"]
    lines += [f"{i + 1},{x:.12e},{y:.12e},{z:.12e}" for i, (x, y, z) in enumerate(fe.node_xyz)]
    lines.append("*ELEMENT, TYPE=C3D10, ELSET=EALL")
    lines += [f"{e + 1}," + ",".join(str(v) for v in row) for e, row in enumerate(conn)]
    lines += ["*MATERIAL, NAME=STEEL", "*ELASTIC", f"{fe.E:.10e},{fe.nu:.10e}",
              "*DENSITY", f"{fe.rho:.10e}", "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL"]
    node_of = np.empty(fe.K_size, dtype=np.int64)
    comp_of = np.empty(fe.K_size, dtype=np.int64)
    for a in range(3):
        node_of[fe.node_dofs[:, a]] = np.arange(fe.n_nodes)
        comp_of[fe.node_dofs[:, a]] = a
    lines.append("*BOUNDARY")
    lines += [f"{node_of[d] + 1},{comp_of[d] + 1},{comp_of[d] + 1},0.0" for d in fixed_dofs]
    for k, name in enumerate(case_names):
        lines += [f"** case {name}", "*STEP", "*STATIC", "*CLOAD, OP=NEW"]
        b = B[:, k]
        nz = np.nonzero(b)[0]
        lines += [f"{node_of[d] + 1},{comp_of[d] + 1},{b[d]:.12e}" for d in nz]
        lines += ["*NODE FILE", "U", "*EL FILE", "S", "*END STEP"]
    Path(path).write_text("\n".join(lines) + "\n")


def run_ccx(inp: Path, timeout: float = 600.0) -> Path:
    """Run ``ccx`` on ``inp`` (its folder as working directory); returns the ``.frd``."""
    exe = shutil.which("ccx")
    if exe is None:
        raise RuntimeError("ccx (CalculiX) not found: apt-get install calculix-ccx")
    inp = Path(inp)
    job = inp.with_suffix("")
    r = subprocess.run([exe, "-i", job.name], cwd=inp.parent, capture_output=True, text=True,
                       timeout=timeout, env={"OMP_NUM_THREADS": "1", "PATH": "/usr/bin:/bin"})
    frd = job.with_suffix(".frd")
    if r.returncode != 0 or not frd.exists() or "ERROR" in r.stdout:
        tail = "\n".join((r.stdout + r.stderr).splitlines()[-15:])
        raise RuntimeError(f"ccx failed (exit {r.returncode}):\n{tail}")
    return frd


def read_frd_stress(path: Path) -> list[tuple[np.ndarray, np.ndarray]]:
    """Every STRESS block of an ASCII ``.frd``: [(node numbers (n,), stresses (n, 6) in the
    file's units: SXX SYY SZZ SXY SYZ SZX)] in step order."""
    src = str(path)
    try:
        text = Path(path).read_text(errors="replace").splitlines()
    except OSError as exc:
        raise InputFileError(src, str(exc)) from None
    blocks = []
    i = 0
    while i < len(text):
        line = text[i]
        if line.startswith(" -4") and line[3:].split()[:1] == ["STRESS"]:
            i += 1
            while i < len(text) and text[i].startswith(" -5"):
                i += 1
            ids, vals = [], []
            while i < len(text) and text[i].startswith(" -1"):
                ln = text[i]
                wide = len(ln) >= 13 + 72
                nw = 10 if wide else 5
                try:
                    ids.append(int(ln[3:3 + nw]))
                    vals.append([float(ln[3 + nw + 12 * k: 3 + nw + 12 * (k + 1)])
                                 for k in range(6)])
                except ValueError:
                    raise InputFileError(src, f"bad stress record: {ln!r}", i + 1) from None
                i += 1
            blocks.append((np.asarray(ids, dtype=np.int64), np.asarray(vals)))
            continue
        i += 1
    if not blocks:
        raise InputFileError(src, "no STRESS block (was *EL FILE S requested?)")
    return blocks


def frd_influence(path: Path, case_names: Sequence[str], stress_scale: float = 1.0,
                  node_xyz: np.ndarray | None = None) -> InfluenceSet:
    """Unit-case stresses from a ``.frd`` (one STRESS block per case, in order) as an
    `InfluenceSet` (Pa per unit load; ``stress_scale`` converts, e.g. 1e6 for MPa)."""
    blocks = read_frd_stress(path)
    if len(blocks) != len(case_names):
        raise InputFileError(str(path), f"{len(blocks)} STRESS blocks for "
                                        f"{len(case_names)} load cases")
    ids = blocks[0][0]
    for b in blocks[1:]:
        if not np.array_equal(b[0], ids):
            raise InputFileError(str(path), "the cases' node lists differ")
    coef = np.stack([b[1] for b in blocks]) * stress_scale
    return InfluenceSet(list(case_names), coef, node_xyz, ids, np.ones(ids.size, dtype=bool),
                        {"source": "calculix-frd", "file": str(path)})


def calculix_unit_cases(pm, workdir: Path, case_idx: Sequence[int] | None = None
                        ) -> tuple[list[str], np.ndarray]:
    """Solve the part's unit cases (or those indexed) with ccx on our mesh; returns
    (case names, nodal stresses (n_cases, n_nodes, 6) [Pa] in our node order)."""
    from .build import load_vectors, support_nodes

    names, B = load_vectors(pm)
    idx = list(range(len(names))) if case_idx is None else list(case_idx)
    names = [names[k] for k in idx]
    Bb = pm.fe.balanced_loads(B[:, idx])
    fixed = pm.fe.three_two_one(support_nodes(pm.fe.node_xyz))
    workdir = Path(workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    inp = workdir / "part.inp"
    write_inp(inp, pm.fe, Bb, fixed, names)
    inf = frd_influence(run_ccx(inp), names)
    out = np.zeros((len(names), pm.fe.n_nodes, 6))
    out[:, inf.node_ids - 1] = inf.coefficients
    return names, out
