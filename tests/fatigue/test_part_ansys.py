"""The ANSYS ``.rst`` importer (#26 item 3) on a real MAPDL result file: the one shipped in
the ansys-mapdl-reader wheel (``examples/file.rst``: MAPDL 15.0, a 1 x 1 x 5 beam of
2 x 2 x 10 SOLID186 20-node hexahedra, 321 nodes, modal analysis, 6 result sets). Its sets
are mode shapes, not unit loads, so it is read with ``static_only=False``; the reading is the
same for a static file's load steps."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest
from ansys.mapdl.reader import examples, read_binary

from cosim.errors import InputFileError
from nodes.fatigue import worker
from nodes.fatigue.config import FatigueConfig
from nodes.fatigue.lib.equivalent_stress import von_mises
from nodes.fatigue.parts import ansys_rst
from nodes.fatigue.parts.ansys_rst import rst_header, rst_influence

pytestmark = pytest.mark.filterwarnings("ignore:`UnstructuredGrid.offset` is deprecated")
RST = Path(examples.rstfile)
CASES = [f"mode_{k}" for k in range(1, 7)]


@pytest.fixture(scope="module")
def reader():
    return read_binary(str(RST))


@pytest.fixture(scope="module")
def inf():
    return rst_influence(RST, CASES, static_only=False)


def tensor(s: np.ndarray) -> np.ndarray:
    """(..., 6) xx yy zz xy yz zx -> (..., 3, 3)."""
    xx, yy, zz, xy, yz, zx = (s[..., i] for i in range(6))
    return np.stack([np.stack([xx, xy, zx], -1), np.stack([xy, yy, yz], -1),
                     np.stack([zx, yz, zz], -1)], -2)


def test_coefficients_are_the_readers_nodal_stress(reader, inf):
    assert inf.case_names == CASES
    assert inf.meta["source"] == "ansys-rst" and inf.meta["analysis"] == "modal"
    for k in range(6):
        nnum, s = reader.nodal_stress(k)
        have = ~np.isnan(s).any(axis=1)
        np.testing.assert_array_equal(inf.node_ids, nnum[have])
        # reader X Y Z XY YZ XZ -> ours xx yy zz xy yz zx: XZ is zx, columns in place
        np.testing.assert_array_equal(inf.coefficients[k], s[have][:, [0, 1, 2, 3, 4, 5]])
    scaled = rst_influence(RST, CASES, stress_scale=1e-6, length_unit="mm", static_only=False)
    np.testing.assert_allclose(scaled.coefficients, inf.coefficients * 1e-6, rtol=1e-15)
    np.testing.assert_allclose(scaled.node_xyz, inf.node_xyz * 1e-3, rtol=1e-15)


def test_nodes_corner_nodes_and_coordinates(reader, inf):
    # 2 x 2 x 10 quadratic hexahedra: 3 x 3 x 11 = 99 corner nodes carry the stress; the 222
    # midside nodes have none in an MAPDL file and are dropped
    assert inf.n_nodes == 99 and inf.meta["n_nodes_in_file"] == 321
    assert inf.meta["n_nodes_dropped_no_stress"] == 222
    assert inf.meta["element_types"] == [186]
    idx = np.searchsorted(reader.mesh.nnum, inf.node_ids)
    np.testing.assert_array_equal(reader.mesh.nnum[idx], inf.node_ids)
    np.testing.assert_array_equal(inf.node_xyz, reader.mesh.nodes[idx, :3])
    grid = reader.grid
    pts = np.asarray(grid.points)[np.searchsorted(grid.point_data["ansys_node_num"],
                                                  inf.node_ids)]
    np.testing.assert_array_equal(inf.node_xyz, pts)
    # the corner nodes of the 1 x 1 x 5 beam: a 0.5 x 0.5 x 0.5 lattice
    for a, n in ((0, 3), (1, 3), (2, 11)):
        np.testing.assert_allclose(np.unique(inf.node_xyz[:, a]), np.linspace(0, n // 2, n))


def test_surface_is_the_beams_exterior(inf):
    x, y, z = inf.node_xyz.T
    exterior = np.isclose(x, 0) | np.isclose(x, 1) | np.isclose(y, 0) | np.isclose(y, 1) \
        | np.isclose(z, 0) | np.isclose(z, 5)
    np.testing.assert_array_equal(inf.surface, exterior)
    assert inf.surface.sum() == 90 == inf.meta["n_surface_nodes"]  # 9 on the axis inside


def test_stress_physics(reader, inf):
    c = inf.coefficients
    assert np.isfinite(c).all() and np.abs(c).max() > 1e8
    T = tensor(c)
    np.testing.assert_array_equal(T, np.swapaxes(T, -1, -2))
    for k in range(6):
        _, p = reader.principal_nodal_stress(k)  # S1 S2 S3 SINT SEQV
        p = p[~np.isnan(p).any(axis=1)]
        np.testing.assert_allclose(von_mises(c[k]), p[:, 4], rtol=1e-9, atol=1e-6 * p[:, 4].max())
        # the principal stresses depend on which shear is where: any other order of the
        # three shears misses them by > 0.1 % of the peak in the bending modes (1e-6 here)
        scale = np.abs(p[:, :3]).max()
        ev = np.linalg.eigvalsh(T[k])[:, ::-1]
        np.testing.assert_allclose(ev, p[:, :3], rtol=0, atol=1e-6 * scale)
        for perm in ([3, 5, 4], [4, 3, 5], [4, 5, 3], [5, 3, 4], [5, 4, 3]):
            wrong = np.linalg.eigvalsh(tensor(c[k][:, [0, 1, 2, *perm]]))[:, ::-1]
            if k in (0, 1, 3, 4):  # the bending modes (torsion: yz = zx; axial: no shear)
                assert np.abs(wrong - p[:, :3]).max() > 1e-3 * scale, (k, perm)
    # the modes' stresses are the beam's (axis z): mode 4 bends in the x-z plane (its
    # displacement mostly x), so the transverse shear is τzx; mode 5 the same in y-z (τyz);
    # mode 3 twists (shear τyz = τzx, no σz); mode 6 stretches (σz)
    mean = np.abs(c).mean(axis=1)  # (cases, 6): xx yy zz xy yz zx
    u = np.abs(reader.nodal_displacement(3)[1]).max(axis=0)
    assert u[0] > 4 * u[1]
    assert mean[3, 5] > 5 * mean[3, 4] and mean[4, 4] > 5 * mean[4, 5]
    assert mean[2, 4] == pytest.approx(mean[2, 5], rel=1e-6)
    assert mean[2, 2] < 1e-3 * mean[2, 4] and mean[2, 3] < 0.02 * mean[2, 4]
    assert mean[5, 2] > 50 * mean[5, 3:].max()
    # the square beam's two first bending modes share their frequency: the same peak stress
    f = inf.meta["time_values"]
    assert f[0] == pytest.approx(f[1], rel=1e-9) and f[3] == pytest.approx(f[4], rel=1e-9)
    vm = von_mises(c)
    assert vm[0].max() == pytest.approx(vm[1].max(), rel=1e-6)
    assert vm[3].max() == pytest.approx(vm[4].max(), rel=1e-6)


def test_fatigue_chain_takes_it(monkeypatch, inf):
    """The set through the worker (superposition, equivalent stress, rainflow, Miner): one
    channel loaded by a fully reversed sine gives at each surface node an equivalent-stress
    range of 2 A |σ|max principal — the reader's S1 / S3 — and damage where it is largest."""
    imported = rst_influence(RST, CASES, stress_scale=1e-3, static_only=False)

    def load(cfg):
        worker.warm_up()
        return imported.subset(imported.surface)

    monkeypatch.setattr(worker, "load_influence", load)
    cfg = FatigueConfig.from_dict({"track_length_m": 100.0})
    t = np.arange(2000) * 1e-3
    amp = 1000.0  # x 1e-3 Pa per unit: the mode's own stress, up to 317 MPa
    res = worker.analyse(t, {"plant/arm/mode_1": amp * np.sin(2 * np.pi * 10 * t)}, cfg, 100.0)
    assert res.damage.shape == (90,) and np.isfinite(res.damage).all()
    assert sorted(res.missing_channels) == [f"plant/arm/{c}" for c in CASES[1:]]
    _, p = read_binary(str(RST)).principal_nodal_stress(0)
    p = p[~np.isnan(p).any(axis=1)][inf.surface]
    eq = np.maximum(np.abs(p[:, 0]), np.abs(p[:, 2]))
    np.testing.assert_allclose(res.eq_range_max, 2 * eq, rtol=1e-6, atol=1e-6 * eq.max())
    crit = int(np.argmax(res.damage))
    assert res.damage[crit] > 0 and eq[crit] == pytest.approx(eq.max(), rel=1e-9)


def test_case_count_and_analysis_type_are_named():
    with pytest.raises(InputFileError, match=r"6 result sets for 3 load cases") as e:
        rst_influence(RST, CASES[:3], static_only=False)
    assert str(RST) in str(e.value)
    with pytest.raises(InputFileError, match=r"a modal analysis \(6 result sets\)"):
        rst_influence(RST, CASES)
    hdr = rst_header(RST)
    assert (hdr["kan"], hdr["nsets"]) == (2, 6) and hdr["end_bytes"] <= hdr["size"]


def test_damaged_files_are_named(tmp_path):
    raw = RST.read_bytes()
    half = tmp_path / "half.rst"
    half.write_bytes(raw[: len(raw) // 2])
    with pytest.raises(InputFileError, match="truncated") as e:
        rst_influence(half, CASES, static_only=False)
    assert "half.rst" in str(e.value)
    # a record length overwritten (result set 1's solution header): the reader's compiled
    # code aborts (std::bad_alloc); read in a child process, that is an error, not a crash
    bad = bytearray(raw)
    ptr = 4 * 81396  # the file's data-set pointer of set 1 (words)
    bad[ptr:ptr + 4] = struct.pack("<i", 0x7FFFFFFF)
    broken = tmp_path / "broken.rst"
    broken.write_bytes(bytes(bad))
    with pytest.raises(InputFileError, match="not a readable MAPDL result file") as e:
        rst_influence(broken, CASES, static_only=False)
    assert "broken.rst" in str(e.value)
    text = tmp_path / "text.rst"
    text.write_text("not a result file\n" * 50)
    with pytest.raises(InputFileError, match="not an ANSYS binary file"):
        rst_influence(text, CASES, static_only=False)
    with pytest.raises(InputFileError, match="missing.rst: part results .*file not found"):
        rst_influence(tmp_path / "missing.rst", CASES, static_only=False)


def test_missing_reader_says_how_to_install(monkeypatch):
    def find_spec(name, *args):
        raise ModuleNotFoundError(f"No module named {name!r}")

    monkeypatch.setattr(ansys_rst.importlib.util, "find_spec", find_spec)
    with pytest.raises(ModuleNotFoundError, match="pip install ansys-mapdl-reader"):
        rst_influence(RST, CASES, static_only=False)
