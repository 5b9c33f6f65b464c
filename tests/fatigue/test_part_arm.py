"""The built-in lower arm as a part (#26 item 2): its part file, its CAD's forging rules and
where the CAD's unfilleted re-entrant edges lie (FE numbers: docs/parts.md, `suscosim part
check nodes/fatigue/parts/data/lower_arm.toml`)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from cosim import lower_arm
from cosim.errors import InputFileError
from nodes.fatigue.parts import cad_arm
from nodes.fatigue.parts.schema import load_part

ARM = cad_arm.DATA / "lower_arm.toml"


def test_part_file_names_every_builtin_channel_and_the_plant_hardpoints():
    from nodes.plant.double_wishbone import DoubleWishboneCorner

    corner = DoubleWishboneCorner()
    try:
        published = set(corner.loads()["arm"])  # every joint load the plant publishes
    finally:
        corner.close()
    part = load_part(ARM)
    assert set(part.channels) == published and len(published) == 15
    for j in part.joints:
        np.testing.assert_array_equal(j.centre, lower_arm.HARDPOINTS[j.name if j.name !=
                                      "bump_stop" else "bump_stop"])
    # the torsion bar's moment acts at both eyes (divided equally by the FE)
    assert [j.name for j in part.joints if "torsion_bar_mx" in j.moments.values()] == \
        ["bush_front", "bush_rear"]
    assert sum(j.mass_kg for j in part.joints) == pytest.approx(0.70)


def test_cad_parameters_enforce_forging_rules(tmp_path):
    text = cad_arm.DEFAULT_PARAMS.read_text()
    bad = tmp_path / "p.toml"
    bad.write_text(text.replace("web = 0.006", "web = 0.003"))
    with pytest.raises(InputFileError, match="web"):
        cad_arm.load_params(bad)
    bad.write_text(text.replace("fillet = 0.005", "fillet = 0.002", 1))
    with pytest.raises(InputFileError, match="fillet"):
        cad_arm.load_params(bad)
    bad.write_text(text.replace("junction_fillet = 0.005", "junction_fillet = 0.0"))
    with pytest.raises(InputFileError, match="junction_fillet"):
        cad_arm.load_params(bad)
    # the hole rib: one width or one per hole corner, never another count
    bad.write_text(re.sub(r"(?m)^hole_rib_width = (\[[^\]]*\]|\S+)",
                        "hole_rib_width = [0.008, 0.008]", text))
    with pytest.raises(InputFileError, match="hole_rib_width"):
        cad_arm.load_params(bad)


def test_cad_fillets_every_web_root_and_leaves_sharp_edges_only_in_joint_zones():
    """One OCC fillet pass before the bores: the solid must be valid (the same pass with the
    bores cut first gave 7.19 kg for a 4.85 kg part, its pivot bore filled), every web root and
    rib-eye/housing junction filleted, and what stays sharp lies within a joint zone."""
    import gmsh  # type: ignore[import-untyped]

    from nodes.fatigue.parts.features import sharp_reentrant_edges

    p = cad_arm.load_params()
    t = p["section"]["web"]
    part = {j.name: j for j in load_part(ARM).joints}
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("bare")
        bare = cad_arm.build(p, fillet=False)["volume"][0]
        mass0 = gmsh.model.occ.getMass(3, bare) * 7850.0
        sharp0 = sharp_reentrant_edges(bare)
        gmsh.model.remove()
        gmsh.model.add("arm")
        tags = cad_arm.build(p)
        v = tags["volume"][0]
        assert len(tags["volume"]) == 1 and len(tags["root_curves"]) >= 8
        assert len(gmsh.model.getEntities(3)) == 1
        mass = gmsh.model.occ.getMass(3, v) * 7850.0
        # the bores are open: their axes' points are outside the material
        hp = lower_arm.HARDPOINTS
        for q in (hp["bush_front"], hp["bush_rear"], hp["ball_joint"],
                  0.5 * (hp["bush_front"] + hp["bush_rear"])):
            assert gmsh.model.isInside(3, v, list(map(float, q))) == 0, q
        sharp = sharp_reentrant_edges(v)
    finally:
        gmsh.finalize()
    # 5 and 3 mm fillets on ~3 m of edges add ~0.1 kg (r^2 (1 - pi/4) per metre), not kilograms
    assert 0.0 < mass - mass0 < 0.03 * mass0, (mass0, mass)
    assert 3.5 < mass < 4.8 + 1e-9  # the forging alone; + 0.7 kg hardware <= 5.5 kg
    assert len(sharp0) >= 30 and len(sharp) <= 8  # the pass took (nearly) every edge
    for e in sorted(sharp, key=lambda e: e["curve"]):
        pts = e["points_m"]
        # none left on the web's surfaces (every rib root there is filleted) ...
        assert not np.all(np.abs(np.abs(pts[:, 2]) - t / 2) < 1e-6)
        # ... and every one within a joint zone of a bore: distance to the bore surface
        def bore_gap(name: str, bore: float, pts: np.ndarray = pts) -> float:
            j = part[name]
            r = pts - j.centre
            d = np.linalg.norm(r - np.outer(r @ j.axis, j.axis), axis=1)
            return float(np.max(d - bore))
        gaps = [bore_gap("bush_front", p["bush_eye"]["bore_radius"]),
                bore_gap("bush_rear", p["bush_eye"]["bore_radius"]),
                bore_gap("ball_joint", p["ball_joint"]["bore_radius"])]
        zones = [part["bush_front"].zone, part["bush_rear"].zone, part["ball_joint"].zone]
        assert any(0 <= g <= z for g, z in zip(gaps, zones, strict=True)), (e["midpoint_m"], gaps)
