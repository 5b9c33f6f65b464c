"""Point-contact and fixed-footprint tyres, lift-off, and build_tyre."""

import numpy as np
import pytest

from cosim.errors import ScenarioError
from nodes.tyre_road.config import build_tyre
from nodes.tyre_road.tyres import FixedFootprint, point_contact_force


def test_point_contact_static_dynamic_and_lift_off():
    F, k = point_contact_force(np.array([0.0, 0.01, 0.05]), np.zeros(3), 2e5, 4000.0)
    assert np.allclose(F, [4000.0, 2000.0, 0.0])
    assert np.allclose(k, [2e5, 2e5, 0.0])
    F, _ = point_contact_force(0.0, 0.02, 192000.0, 3560.0)
    assert F == pytest.approx(3560.0 + 3840.0)


def test_fixed_footprint_staircase_on_a_step():
    tyre = FixedFootprint(n=4, contact_length=0.3, k_t=2e5)
    assert np.allclose(tyre.contact_offsets, [0.15, 0.05, -0.05, -0.15])
    W, h = 4000.0, 0.02
    forces = []
    for n_on in range(5):
        z_g = np.array([h] * n_on + [0.0] * (4 - n_on))
        F, k = tyre.force(np.array(0.0), z_g, np.array(W))
        forces.append(float(F))
        assert float(k) == pytest.approx(2e5)
    assert np.allclose(np.diff(forces), 2e5 / 4 * h)  # four equal stages
    assert forces[-1] == pytest.approx(W + 2e5 * h)   # full footprint = point contact


def test_fixed_footprint_partial_and_full_lift_off():
    tyre = FixedFootprint(n=4, contact_length=0.2, k_t=2e5)
    # two springs over a 50 mm hole lose contact; the others carry on
    F, k = tyre.force(np.array(0.0), np.array([0.0, -0.05, -0.05, 0.0]), np.array(4000.0))
    assert float(F) == pytest.approx(2000.0)
    assert float(k) == pytest.approx(1e5)
    F, k = tyre.force(np.array(0.05), np.zeros(4), np.array(4000.0))
    assert float(F) == 0.0 and float(k) == 0.0


def test_build_tyre():
    t = build_tyre({"model": "fixed_footprint", "stiffness": 239000, "n": 4,
                    "contact_length": 0.2})
    assert t.k_t == 239000 and len(t.contact_offsets) == 4
    assert build_tyre({"model": "point_contact", "stiffness": 239000}).k_t == 239000
    for cfg, key in [({"model": "radial", "stiffness": 1}, "tyre.model"),
                     ({"model": "point_contact"}, "tyre.stiffness"),
                     ({"model": "fixed_footprint", "stiffness": 1, "n": 0,
                       "contact_length": 0.2}, "tyre.n"),
                     ({"model": "fixed_footprint", "stiffness": 1, "n": 4}, "tyre.contact_length")]:
        with pytest.raises(ScenarioError) as e:
            build_tyre(cfg)
        assert e.value.key == key
