"""Local refinement of a gmsh mesh (#26 item 2: the convergence table's meshes and the part
file's mesh recipe ``mesh.refine_centres``): a ball refines inside it only. gmsh clamps every
element size, its curvature sizing's too, to ``Mesh.MeshSizeMin``; lowering that floor for the
balls used to refine every curved face of the part (the arm: 4312 -> 8866 vertices for a ball
outside it). On the test link at 30 mm the bores' curvature sizing (12 elements per circle:
5.2 mm on the 10 mm bores) sits below the unrefined floor (7.5 mm), so the old floor showed
there too (427 -> 570 vertices)."""

from __future__ import annotations

import numpy as np
import pytest

from cosim.errors import InputFileError
from nodes.fatigue.parts.build import part_model
from nodes.fatigue.parts.mesh import RAMP, floor_at
from nodes.fatigue.parts.schema import load_part

from .test_part_user import make_link, write_part


@pytest.fixture(scope="module")
def link(tmp_path_factory):
    folder = tmp_path_factory.mktemp("link_refine")
    make_link(folder)
    return folder, write_part(folder)


def test_ball_outside_the_part_leaves_the_mesh_as_it_was(link):
    _, path = link
    part = load_part(path)
    plain = part_model(part, 0.03)
    away = part_model(part, 0.03, refine=[(0.5, 0.5, 0.5, 0.001, 0.002)])
    n0, n1 = plain.mesh.p.shape[0], away.mesh.p.shape[0]
    assert abs(n1 - n0) <= 0.03 * n0, (n0, n1)
    # the curved bores keep their unrefined size: the smallest surface edge is the same
    def shortest(pm):
        p, t = pm.mesh.p, pm.mesh.t
        return min(np.linalg.norm(p[t[:, a]] - p[t[:, b]], axis=1).min()
                   for a, b in ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)))
    assert shortest(away) > 0.7 * shortest(plain)


def test_ball_on_the_surface_refines_inside_and_not_the_bores(link):
    _, path = link
    part = load_part(path)
    plain = part_model(part, 0.03)
    # on the bar's top face, mid-way between the eyes; 20 mm: gmsh sees a size field at the
    # vertices it has, so a ball much smaller than the elements round it is not seen
    ball = (0.1, 0.0, 0.01, 0.02, 0.003)
    fine = part_model(part, 0.03, refine=[ball])

    def edges(pm, centre, r, inside=True):
        p, t = pm.mesh.p, pm.mesh.t
        c = p[t].mean(axis=1)
        d = np.linalg.norm(c - centre, axis=1)
        sel = d < r if inside else d > r
        return np.linalg.norm(p[t[sel, 0]] - p[t[sel, 1]], axis=1), int(sel.sum())

    centre = np.array(ball[:3])
    e_in, n_in = edges(fine, centre, 0.015)
    e_in0, n_in0 = edges(plain, centre, 0.015)
    assert np.median(e_in) < 0.006 < np.median(e_in0) and n_in > 10 * max(n_in0, 1)
    # away from the ball and its ramp (the eyes): the same element sizes as unrefined
    far = 0.02 + RAMP * 0.03 + 0.03
    e_out, _ = edges(fine, centre, far, inside=False)
    e_out0, _ = edges(plain, centre, far, inside=False)
    assert abs(np.median(e_out) / np.median(e_out0) - 1.0) < 0.1


def test_floor_field_is_the_balls_inside_and_the_global_floor_outside():
    balls = np.array([[0.0, 0.0, 0.0, 0.01, 0.002]])
    assert floor_at(balls, 0.03, 0.005, np.array([0.0, 0.0, 0.0])) == 0.001
    assert floor_at(balls, 0.03, 0.005, np.array([0.1, 0.0, 0.0])) == 0.005
    mid = floor_at(balls, 0.03, 0.005, np.array([0.01 + 0.5 * RAMP * 0.03, 0.0, 0.0]))
    assert mid == pytest.approx(0.003)


def test_recipe_keys_are_read_and_checked(link, tmp_path):
    folder, _ = link
    p = write_part(folder, mesh="size = 0.03\nfillet_size = 0.01\nrefine_centres = "
                                "[[0.1, 0.0, 0.01]]\nrefine_radius = 0.02\n"
                                "refine_size = 0.003")
    part = load_part(p)
    assert part.refine == [(0.1, 0.0, 0.01, 0.02, 0.003)]
    pm = part_model(part)  # the recipe by default
    assert pm.mesh.p.shape[0] > 1.2 * part_model(part, refine=()).mesh.p.shape[0]
    for mesh, key in (("refine_centres = [[0.1, 0.0]]\nrefine_radius = 0.01\n"
                       "refine_size = 0.003", "refine_centres"),
                      ("refine_centres = [[0.1, 0.0, 0.0]]\nrefine_size = 0.003",
                       "refine_radius"),
                      ("refine_size = 0.003", "refine_size"),
                      ("refine_centres = [[0.1, 0.0, 0.0]]\nrefine_radius = -1\n"
                       "refine_size = 0.003", "refine_radius")):
        bad = write_part(folder, mesh="size = 0.03\n" + mesh)
        with pytest.raises(InputFileError, match=f"mesh.{key}"):
            load_part(bad)
    write_part(folder)  # the module's other tests read link.toml: restore it


def test_convergence_refines_round_the_most_damaged_nodes_too(link):
    """`card.convergence` with a damage function (a run's fatigue pass; here a stand-in
    peaked on the bar's side face at mid-span, on the neutral plane of the static bending,
    away from the static hot spots): the balls take in the global mesh's most damaged nodes,
    and the table reports the finest mesh's ten most damaged nodes, inside the balls, read on
    every mesh at the same points."""
    from nodes.fatigue.parts.card import convergence

    _, path = link
    part = load_part(path)
    loads = {"a_z": 1000.0, "b_z": -1000.0, "a_my": 20.0}
    x0 = np.array([0.1, 0.02, 0.0])

    def damage(inf):
        return np.exp(-np.sum((inf.node_xyz - x0) ** 2, axis=1) / 0.003 ** 2)

    static_only = convergence(part, [0.02], loads, local_sizes=[0.008], radius=0.02)
    rf0 = static_only["refinement"]
    assert not rf0["capped"]
    assert np.min(np.linalg.norm(np.array(rf0["centres_m"]) - x0, axis=1)) > 0.02
    cv = convergence(part, [0.02], loads, local_sizes=[0.01, 0.008], radius=0.02,
                     damage=damage)
    dm = cv["damaged"]
    d = [x["damage"] for x in dm]
    assert len(d) == 10 and d == sorted(d, reverse=True)
    assert all(np.linalg.norm(np.array(d["xyz_m"]) - x0) < 0.01 for d in dm)
    rf = cv["refinement"]
    assert rf["damaged_inside"] and rf["hot_spots_inside"]
    assert rf["n_balls"] > rf0["n_balls"]
    ch = cv["unit_change_two_finest_damaged"]
    assert len(ch) == 10 and all(0.0 <= c < 1.0 for c in ch)
    rows = cv["rows"]
    assert all("peak_damage" in r for r in rows)
    np.testing.assert_allclose(rows[-1]["static_at_damaged_mpa"],
                               [d["static_von_mises_mpa"] for d in dm], rtol=1e-9)
