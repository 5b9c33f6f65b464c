"""The Nastran OP2 importer (nodes/fatigue/parts/nastran_op2.py, issue #44 item 4) on OP2 files
written by pyNastran's OP2 writer: a 3 x 3 x 3 block of CHEXA8 (64 grids, GEOM1/GEOM2 written
as PARAM,POST,-1 does), three static subcases, each a known stress field.

The corner stresses of each element are a linear field of the node coordinates (a different
one per case and component) plus a jump constant over the element: the importer's nodal
average must give the field plus the mean jump of the elements around the node, computed
here by a loop over the elements (independent of the importer's np.add.at). The centre rows
carry 1e9 so that reading them would show.
"""

from __future__ import annotations

import os
from itertools import product
from pathlib import Path

import numpy as np
import pytest

try:  # pyNastran pins numpy<2: .ci/run installs it without its pins (pyproject.toml says why)
    import pyNastran  # noqa: F401
except ImportError:
    if os.environ.get("CI"):
        raise
    pytest.skip("pyNastran not installed (.ci/run installs it: pip install --no-deps "
                "pyNastran==1.4.1 cpylog docopt-ng colorama)", allow_module_level=True)

from cosim.errors import InputFileError
from nodes.fatigue.parts.nastran_op2 import free_face_nodes, op2_influence

N = 3  # elements per side
SUBCASES = (30, 10, 20)  # written out of order: the cases are read by ascending id
rng = np.random.default_rng(44)
FIELD = {sc: (rng.normal(size=6), rng.normal(size=(6, 3))) for sc in SUBCASES}
JUMP = {sc: rng.normal(scale=0.1, size=(N ** 3, 6)) for sc in SUBCASES}


def _grid() -> tuple[dict[tuple[int, int, int], int], np.ndarray]:
    ids, xyz = {}, []
    for k, j, i in product(range(N + 1), repeat=3):
        ids[(i, j, k)] = len(xyz) + 1
        xyz.append((0.5 * i, 0.4 * j, 0.3 * k))
    return ids, np.array(xyz)


def _hexes(ids) -> list[list[int]]:
    out = []
    for k, j, i in product(range(N), repeat=3):
        out.append([ids[(i, j, k)], ids[(i + 1, j, k)], ids[(i + 1, j + 1, k)],
                    ids[(i, j + 1, k)], ids[(i, j, k + 1)], ids[(i + 1, j, k + 1)],
                    ids[(i + 1, j + 1, k + 1)], ids[(i, j + 1, k + 1)]])
    return out


def _write(path: Path, *, subcases=SUBCASES, cid: int = 0) -> None:
    """An OP2 by pyNastran's writer (the numpy 2.4 alias as the importer's child sets it)."""
    with pytest.MonkeyPatch.context() as mp:
        if not hasattr(np, "in1d"):
            mp.setattr(np, "in1d", np.isin, raising=False)
        from pyNastran.op2.op2_geom import OP2Geom
        from pyNastran.op2.tables.oes_stressStrain.real.oes_solids import (
            RealSolidStressArray,
        )
        ids, xyz = _grid()
        m = OP2Geom(debug=None)
        for n in range(1, len(xyz) + 1):
            m.add_grid(n, list(xyz[n - 1]))
        m.add_psolid(1, 1)
        m.add_mat1(1, 2.1e5, None, 0.3)
        hexes = _hexes(ids)
        rows = []
        for e, nodes in enumerate(hexes, start=1):
            m.add_chexa(e, 1, nodes)
            rows += [(e, 0)] + [(e, n) for n in nodes]
        en = np.array(rows, dtype=np.int32)
        for sc in subcases:
            a, b = FIELD[sc]
            data = np.zeros((1, len(en), 10), dtype=np.float32)
            for r, (e, n) in enumerate(en):
                data[0, r, :6] = 1e9 if n == 0 else a + b @ xyz[n - 1] + JUMP[sc][e - 1]
            cids = np.array([[e, cid] for e in range(1, len(hexes) + 1)], dtype=np.int32)
            obj = RealSolidStressArray.add_static_case(
                "OES1X1", "CHEXA", en, cids, data, sc, is_sort1=True, is_msc=True,
                title="unit case", subtitle="", label="")
            obj.num_wide = 4 + 21 * 9  # the centre and 8 corners (its add_static_case says 3)
            m.op2_results.stress.chexa_stress[sc] = obj
        m.write_op2(str(path), post=-1, endian=b"<", nastran_format="msc")


@pytest.fixture(scope="module")
def op2(tmp_path_factory) -> Path:
    p = tmp_path_factory.mktemp("op2") / "block.op2"
    _write(p)
    return p


def test_the_nodal_average_of_a_known_field(op2) -> None:
    inf = op2_influence(op2, ["case_10", "case_20", "case_30"], stress_scale=1e6)
    ids, xyz = _grid()
    hexes = _hexes(ids)
    assert inf.case_names == ["case_10", "case_20", "case_30"]
    assert inf.node_ids.tolist() == list(range(1, (N + 1) ** 3 + 1))
    assert inf.node_xyz is not None
    np.testing.assert_allclose(inf.node_xyz, xyz, rtol=1e-6)
    for c, sc in enumerate(sorted(SUBCASES)):
        a, b = FIELD[sc]
        for n in range(1, len(xyz) + 1):
            around = [e for e, nodes in enumerate(hexes) if n in nodes]
            want = a + b @ xyz[n - 1] + JUMP[sc][around].mean(axis=0)
            np.testing.assert_allclose(inf.coefficients[c, n - 1] / 1e6, want, rtol=2e-6,
                                       atol=2e-6)
    # the surface: every grid on the box's faces, not the 2 x 2 x 2 inside
    inside = [ids[(i, j, k)] for i, j, k in product(range(1, N), repeat=3)]
    assert int((~inf.surface).sum()) == (N - 1) ** 3
    assert sorted(inf.node_ids[~inf.surface].tolist()) == sorted(inside)
    assert inf.meta["subcases"] == [10, 20, 30]


def test_length_unit_scales_the_coordinates(op2) -> None:
    inf = op2_influence(op2, ["a", "b", "c"], length_unit="mm")
    np.testing.assert_allclose(inf.node_xyz, _grid()[1] * 1e-3, rtol=1e-6)


def test_the_free_faces_of_two_tets_sharing_one() -> None:
    conn = np.array([[1, 2, 3, 4, -1, -1, -1, -1], [1, 2, 3, 5, -1, -1, -1, -1],
                     [6, 7, 8, 9, 10, 11, 12, 13]])
    got = free_face_nodes(np.array([4, 4, 8]), conn)
    assert got.tolist() == list(range(1, 14))  # every node of two tets and a lone hex
    two = free_face_nodes(np.array([8, 8]), np.array([[1, 2, 3, 4, 5, 6, 7, 8],
                                                      [5, 6, 7, 8, 9, 10, 11, 12]]))
    assert two.tolist() == list(range(1, 13))


def test_errors_name_the_file(op2, tmp_path) -> None:
    with pytest.raises(InputFileError, match="3 result sets .* for 2 load cases"):
        op2_influence(op2, ["a", "b"])
    cid = tmp_path / "cordm.op2"
    _write(cid, subcases=(10,), cid=7)
    with pytest.raises(InputFileError, match=r"coordinate system\(s\) \[7\]"):
        op2_influence(cid, ["a"])
    text = tmp_path / "notes.op2"
    text.write_text("not an op2\n")
    with pytest.raises(InputFileError, match="notes.op2.*not a readable Nastran OP2 file"):
        op2_influence(text, ["a"])
    with pytest.raises(InputFileError, match="file not found"):
        op2_influence(tmp_path / "none.op2", ["a"])


def test_centre_output_only_is_refused(op2, monkeypatch) -> None:
    """pyNastran's writer always writes the corners of a CHEXA, so the reader's rows of a
    STRESS(CENTER) file (grid 0 only) are given to the importer directly."""
    import nodes.fatigue.parts.nastran_op2 as mod

    def centre_rows(*args, **kwargs):
        return {"subcase": np.array([1]), "step": np.array([0]), "analysis": np.array([1]),
                "set": np.zeros(2, dtype=int), "nid": np.zeros(2, dtype=int),
                "cid": np.zeros(2, dtype=int), "stress": np.ones((2, 6)),
                "grid": np.zeros(0, dtype=int), "xyz": np.zeros((0, 3)),
                "el_corners": np.zeros(0, dtype=int), "conn": np.zeros((0, 8), dtype=int)}
    monkeypatch.setattr(mod, "read_in_child", centre_rows)
    with pytest.raises(InputFileError, match="element centres only"):
        op2_influence(op2, ["a"])
