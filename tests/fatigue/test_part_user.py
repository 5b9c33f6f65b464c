"""A part the project has never seen: a STEP made here with gmsh + a joints TOML, through
`load_part`, the influence API and `suscosim part check`, with no code change (#26 item 5).
Also the schema's errors, the FE's mass against the CAD's volume and its first mode against
beam theory."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from cosim.errors import InputFileError
from nodes.fatigue.parts.build import part_influence, part_model
from nodes.fatigue.parts.schema import load_part
from orchestrator.studies.part_check import main as part_main

E, NU, RHO = 2.1e11, 0.3, 7850.0
JOINTS = """
[[joint]]
name = "a"
centre = [0.0, 0.0, 0.0]
axis = [0, 0, 1]
radius = 0.0105
length = 0.05
forces = { x = "a_x", z = "a_z" }
moments = { y = "a_my" }

[[joint]]
name = "b"
centre = [0.2, 0.0, 0.0]
axis = [0, 0, 1]
radius = 0.0105
length = 0.05
forces = { z = "b_z" }
moments = { z = "b_mz", y = "b_my" }
"""


def make_link(folder: Path) -> float:
    """A link with two eyes (STEP, metres); returns its CAD volume [m^3]."""
    import gmsh

    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        occ = gmsh.model.occ
        bar = occ.addBox(0, -0.02, -0.01, 0.2, 0.04, 0.02)
        eyes = [(3, occ.addCylinder(x, 0, -0.02, 0, 0, 0.04, 0.02)) for x in (0.0, 0.2)]
        s, _ = occ.fuse([(3, bar)], eyes)
        holes = [(3, occ.addCylinder(x, 0, -0.03, 0, 0, 0.06, 0.01)) for x in (0.0, 0.2)]
        s, _ = occ.cut(s, holes)
        occ.synchronize()
        vol = occ.getMass(3, s[0][1])
        gmsh.option.setString("Geometry.OCCTargetUnit", "M")
        gmsh.write(str(folder / "link.step"))
        return float(vol)
    finally:
        gmsh.finalize()


LINK_MESH = "size = 0.02\nfillet_size = 0.01"
"""A coarse mesh of the link (20 mm on its 20 x 40 mm bar: ~800 assessed nodes, a 1.3 s solve
against 5 s at the default 12 mm), for the tests whose claims are about which parts and
channels reach which results, not the link's stress."""


def write_part(folder: Path, extra: str = JOINTS, mesh: str = "size = 0.012\nfillet_size = 0.006"
               ) -> Path:
    p = folder / "link.toml"
    p.write_text(f"""[part]
name = "link"
geometry = "link.step"
material = {{ name = "steel", E = {E}, nu = {NU}, rho = {RHO}, Sy = 3.5e8 }}
[mesh]
{mesh}
{extra}""")
    return p


@pytest.fixture(scope="module")
def link(tmp_path_factory):
    folder = tmp_path_factory.mktemp("link")
    vol = make_link(folder)
    return folder, write_part(folder), vol


def test_user_step_through_influence_api(link, tmp_path, monkeypatch):
    folder, path, vol = link
    monkeypatch.setenv("SUSCOSIM_CACHE", str(tmp_path))
    part = load_part(path)
    assert part.channels == ["a_x", "a_z", "a_my", "b_z", "b_mz", "b_my"]
    inf = part_influence(part)
    assert inf.case_names == part.channels
    assert inf.coefficients.shape == (6, inf.n_nodes, 6)
    assert inf.node_xyz is not None and inf.surface.all()
    # the mass is the CAD's volume times rho (the tets are straight-sided: within 1 %)
    assert inf.meta["mass_kg"] == pytest.approx(vol * RHO, rel=0.01)
    # assessed nodes lie outside the joints' 10 mm zones round the bores (radius 10 mm)
    d = np.minimum(np.hypot(inf.node_xyz[:, 0], inf.node_xyz[:, 1]),
                   np.hypot(inf.node_xyz[:, 0] - 0.2, inf.node_xyz[:, 1]))
    assert d.min() > 0.0195
    # +1 N m about y at a, -1 N m at b: pure bending; at mid-span the top fibre's stress
    # is M c / I (beam theory, within 5 %)
    S = inf.coefficients[2] - inf.coefficients[5]
    mid = (np.abs(inf.node_xyz[:, 0] - 0.1) < 0.008) & (inf.node_xyz[:, 2] > 0.0099)
    assert mid.sum() >= 3
    moment = 1.0  # N m
    sigma = moment * 0.01 / (0.04 * 0.02 ** 3 / 12)
    assert np.abs(S[mid, 0]).mean() == pytest.approx(sigma, rel=0.05)
    # the cache answers the second call with the same numbers
    again = part_influence(part)
    np.testing.assert_array_equal(again.coefficients, inf.coefficients)
    assert len(list((tmp_path / "parts").glob("*.npz"))) == 1


def test_user_step_through_part_check(link, capsys):
    _, path, _ = link
    assert part_main(["check", str(path), "--json", "--mesh-size", "0.02"]) == 0
    card = json.loads(capsys.readouterr().out)
    assert card["part"] == "link" and len(card["modes"]) == 6
    assert set(card["joints"]) == {"a", "b"}
    assert "hot_spots" not in card  # the plant publishes none of these channels


def test_box_first_mode_is_beam_theory(tmp_path):
    """A plain bar's first free-free mode against Euler-Bernoulli (22.37 / (2 pi L^2)
    sqrt(EI / (rho A))): within 3 % (L/h = 20: shear and rotary inertia lower it ~1 %)."""
    import gmsh

    L, b, h = 0.3, 0.03, 0.015
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.occ.addBox(0, -b / 2, -h / 2, L, b, h)
        gmsh.model.occ.synchronize()
        gmsh.option.setString("Geometry.OCCTargetUnit", "M")
        gmsh.write(str(tmp_path / "bar.step"))
    finally:
        gmsh.finalize()
    (tmp_path / "bar.toml").write_text(f"""[part]
geometry = "bar.step"
material = {{ E = {E}, nu = {NU}, rho = {RHO}, Sy = 3.5e8 }}
[mesh]
size = 0.0075
[[joint]]
name = "end"
centre = [0.0, 0.0, 0.0]
radius = 0.012
forces = {{ z = "end_z" }}
""")
    pm = part_model(load_part(tmp_path / "bar.toml"))
    f, _ = pm.fe.modes(1)
    EI = E * b * h ** 3 / 12
    f_beam = 22.373 / (2 * math.pi * L ** 2) * math.sqrt(EI / (RHO * b * h))
    assert f[0] == pytest.approx(f_beam, rel=0.03)


@pytest.mark.parametrize("edit, key", [
    ('forces = { x = "a_x", z = "a_z" }', "no forces or moments"),
    ('coupling = "glued"', "coupling"),
    ('radius = -1', "radius"),
    ('centre = "hardpoint:nowhere"', "unknown hardpoint"),
    ('colour = "red"', "unknown key"),
])
def test_bad_joint_is_named(link, tmp_path, edit, key):
    folder, _, _ = link
    (tmp_path / "link.step").write_bytes((folder / "link.step").read_bytes())
    joints = JOINTS
    if edit.startswith("forces"):
        joints = joints.replace(edit + "\n", "").replace('moments = { y = "a_my" }\n', "")
    elif edit.startswith("centre"):
        joints = joints.replace("centre = [0.0, 0.0, 0.0]", edit, 1)
    elif edit.startswith("radius"):
        joints = joints.replace("radius = 0.0105", edit, 1)
    else:
        joints = joints.replace('name = "a"', f'name = "a"\n{edit}', 1)
    p = write_part(tmp_path, joints)
    with pytest.raises(InputFileError, match=key):
        load_part(p)
    assert part_main(["check", str(p)]) == 2


def test_missing_geometry_and_selection(tmp_path, capsys):
    p = write_part(tmp_path)
    with pytest.raises(InputFileError, match="part.geometry: file not found"):
        load_part(p)
    assert part_main(["check", str(p)]) == 2
    assert "part.geometry" in capsys.readouterr().err
    with pytest.raises(InputFileError, match="file not found"):
        load_part(tmp_path / "nope.toml")


def test_amg_paths_match_the_direct_solver(link, monkeypatch):
    """The iterative paths (AMG-CG statics, AMG-LOBPCG modes) that large meshes take give the
    direct solver's answers."""
    import nodes.fatigue.lib.solid as solid

    _, path, _ = link
    pm = part_model(load_part(path), 0.02)
    from nodes.fatigue.parts.build import load_vectors, support_nodes

    _, B = load_vectors(pm)
    sup = support_nodes(pm.fe.node_xyz)
    U_direct, _ = pm.fe.solve_loads(B, sup)
    f_direct, _ = pm.fe.modes(2)
    monkeypatch.setattr(solid, "DIRECT_MAX_DOFS", 0)
    U_amg, _ = pm.fe.solve_loads(B, sup)
    f_amg, _ = pm.fe.modes(2)
    np.testing.assert_allclose(U_amg, U_direct, atol=1e-8 * np.abs(U_direct).max())
    np.testing.assert_allclose(f_amg, f_direct, rtol=1e-6)
    # the LOBPCG path preconditioned by SuperLU (meshes of 40 000 to DIRECT_MAX_DOFS dofs)
    monkeypatch.setattr(solid, "DIRECT_MAX_DOFS", 10 ** 9)
    monkeypatch.setattr(solid, "SHIFT_INVERT_MAX_DOFS", 0)
    f_lu, _ = pm.fe.modes(2)
    np.testing.assert_allclose(f_lu, f_direct, rtol=1e-6)


def test_p2_interpolation_is_exact_for_quadratics_and_clamps_outside(link):
    """The convergence table compares meshes at physical points: the P2 interpolation of a
    nodal field reproduces any quadratic inside the mesh, a node's own value at the node, and
    takes a point just outside at a point of the surface near it (gap reported)."""
    from nodes.fatigue.parts.card import p2_interpolation

    _, path, _ = link
    pm = part_model(load_part(path), 0.02)
    x = pm.fe.node_xyz

    def q(x):
        return 3.0 + 2.0 * x[:, 0] - x[:, 1] + 40.0 * x[:, 0] * x[:, 2] + 90.0 * x[:, 1] ** 2
    f = q(x)
    rng = np.random.default_rng(1)
    pts = np.c_[rng.uniform(0.03, 0.17, 20), rng.uniform(-0.018, 0.018, 20),
                rng.uniform(-0.009, 0.009, 20)]  # inside the bar
    nodes, w, gap = p2_interpolation(pm, np.vstack([pts, x[[5, 77]]]))
    np.testing.assert_allclose(w.sum(axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose((w * f[nodes]).sum(axis=1), q(np.vstack([pts, x[[5, 77]]])),
                               rtol=1e-9)
    assert np.all(gap == 0.0)
    out = np.array([[0.1, 0.0, 0.0105]])  # 0.5 mm above the bar's top face
    _, _, g = p2_interpolation(pm, out)
    assert 0.0005 - 1e-9 <= g[0] < 0.001  # at least the distance to the mesh, and near it


def test_local_refinement_balls_refine_only_inside(link):
    """`mesh.convergence_local`'s meshes: a refinement ball makes the elements inside it
    smaller and leaves the mesh away from it as it was."""
    _, path, _ = link
    part = load_part(path)
    coarse = part_model(part, 0.02)
    fine = part_model(part, 0.02, refine=[(0.1, 0.0, 0.0, 0.01, 0.002)])

    def edge(pm, centre, r):
        p, t = pm.mesh.p, pm.mesh.t
        c = p[t].mean(axis=1)
        inside = np.linalg.norm(c - centre, axis=1) < r
        e = np.linalg.norm(p[t[:, 0]] - p[t[:, 1]], axis=1)
        return np.median(e[inside]), int(inside.sum())

    h_c, n_c = edge(coarse, np.array([0.1, 0.0, 0.0]), 0.008)
    h_f, n_f = edge(fine, np.array([0.1, 0.0, 0.0]), 0.008)
    assert h_f < 0.6 * h_c and n_f > 10 * n_c
    assert h_f < 0.003
    import dataclasses

    with pytest.raises(ValueError, match="CAD"):  # a mesh file is read as it is
        part_model(dataclasses.replace(part, kind="mesh"), 0.02,
                   refine=[(0.1, 0.0, 0.0, 0.01, 0.002)])


def test_local_convergence_table_on_the_link(link):
    """`card.convergence` with local sizes: the global mesh, then two meshes refined round its
    highest-stressed nodes; the ten spots of the finest mesh are read on every mesh at the
    same physical points (on the finest: exactly its nodal values), and lie in the balls."""
    from nodes.fatigue.parts.card import convergence

    _, path, _ = link
    part = load_part(path)
    loads = {"a_z": 1000.0, "b_z": -1000.0, "a_my": 20.0}
    cv = convergence(part, [0.02], loads, local_sizes=[0.005, 0.008], radius=0.01)
    rows = cv["rows"]
    assert [r["local_size_m"] for r in rows] == [None, 0.008, 0.005]
    assert rows[0]["n_nodes"] < rows[1]["n_nodes"] < rows[2]["n_nodes"]
    hot = [h["von_mises_mpa"] for h in cv["hot_spots"]]
    np.testing.assert_allclose(rows[-1]["static_at_spots_mpa"], hot, rtol=1e-9)
    assert rows[-1]["interpolation_gap_max_m"] == 0.0
    rf = cv["refinement"]
    assert rf["n_balls"] >= 1 and rf["hot_spots_inside"]
    ch = cv["unit_change_two_finest"]
    assert len(ch) == 10 and all(0.0 <= c < 1.0 for c in ch)
    assert cv["max_unit_change_two_finest"] == max(ch)
