"""#30 item 6: an ANSYS PRNSOL,S,COMP listing is read (pages, the min/max block skipped);
another listing is refused naming the format expected."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cosim.errors import InputFileError
from nodes.fatigue.prnsol import looks_like_prnsol, read_prnsol

PAGE = """
 PRINT S    NODAL SOLUTION PER NODE

  ***** POST1 NODAL STRESS LISTING *****

  LOAD STEP=     1  SUBSTEP=     1
   TIME=    1.0000      LOAD CASE=   0

  THE FOLLOWING X,Y,Z VALUES ARE IN GLOBAL COORDINATES

    NODE     SX          SY          SZ          SXY         SYZ         SXZ
"""


def listing(rows: np.ndarray, ids: np.ndarray, split: int) -> str:
    def line(i: int) -> str:
        return f"{ids[i]:8d}" + "".join(f" {v:11.4E}" for v in rows[i]) + "\n"

    text = PAGE + "".join(line(i) for i in range(split))
    text += PAGE + "".join(line(i) for i in range(split, len(ids)))
    text += ("\n MINIMUM VALUES\n NODE          3           1           2           4"
             "           5           6\n VALUE  -0.1234E+01 -0.2E+01 -0.3E+01 -0.4E+01"
             " -0.5E+01 -0.6E+01\n\n MAXIMUM VALUES\n NODE 1 2 3 4 5 6\n"
             " VALUE 0.1E+01 0.2E+01 0.3E+01 0.4E+01 0.5E+01 0.6E+01\n")
    return text


def test_prnsol_pages_read(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    rows = np.round(rng.normal(0, 1e3, (9, 6)), 1)
    ids = np.array([3, 5, 8, 13, 21, 34, 55, 89, 144])
    f = tmp_path / "case1.lis"
    f.write_text(listing(rows, ids, 5))
    assert looks_like_prnsol(f)
    got_ids, xyz, s = read_prnsol(f)
    assert xyz is None
    np.testing.assert_array_equal(got_ids, ids)
    np.testing.assert_allclose(s, rows, rtol=1e-4)


def test_principal_listing_refused_naming_the_format(tmp_path: Path) -> None:
    f = tmp_path / "prin.lis"
    f.write_text(PAGE.replace("SX          SY          SZ          SXY         SYZ         SXZ",
                              "S1          S2          S3          SINT        SEQV")
                 + "       1  1.0 2.0 3.0 4.0 5.0\n")
    with pytest.raises(InputFileError) as e:
        read_prnsol(f)
    assert "NODE SX SY SZ SXY SYZ SXZ" in str(e.value) and "prin.lis" in str(e.value)
    g = tmp_path / "empty.lis"
    g.write_text("just words\n")
    with pytest.raises(InputFileError, match="PRNSOL,S,COMP"):
        read_prnsol(g)


def test_an_influence_mapping_takes_a_prnsol_listing_beside_a_csv(tmp_path: Path) -> None:
    """The cases of one mapping, one a PRNSOL listing and one a CSV of the same nodes, give
    the coefficients of their files (before, the listing was "no numeric rows")."""
    from nodes.fatigue.influence import import_influence

    rng = np.random.default_rng(1)
    ids = np.array([3, 5, 8, 13, 21, 34])
    a, b = np.round(rng.normal(0, 1e3, (2, 6, 6)), 1)
    (tmp_path / "z.lis").write_text(listing(a, ids, 4))
    (tmp_path / "x.csv").write_text("node,Sx,Sy,Sz,Sxy,Syz,Szx\n" + "".join(
        f"{i}," + ",".join(str(v) for v in row) + "\n" for i, row in zip(ids, b, strict=True)))
    inf = import_influence(tmp_path, {"plant/arm/ball_joint_z": "z.lis",
                                      "ball_joint_x": {"file": "x.csv", "scale": -1.0}})
    assert inf.case_names == ["ball_joint_z", "ball_joint_x"]
    np.testing.assert_array_equal(inf.node_ids, ids)
    np.testing.assert_allclose(inf.coefficients[0], a, rtol=1e-4)
    np.testing.assert_allclose(inf.coefficients[1], -b)
