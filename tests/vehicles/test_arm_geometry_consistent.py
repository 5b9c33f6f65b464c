"""One definition of the lower arm: the plant's arm points, the PyBullet corner's placement
of the arm and the spring force's lever all come from cosim.lower_arm."""

import numpy as np
import pybullet as p
import pytest

from cosim import lower_arm as la
from nodes.plant import double_wishbone as dw
from nodes.plant import double_wishbone_geometry as geo


@pytest.mark.parametrize("name", sorted(la.HARDPOINTS))
def test_plant_arm_points_in_the_arm_frame_are_cosim_lower_arm(name):
    g = geo.BUILTIN
    assert np.allclose(g.to_arm_frame(g.arm_points[name]), la.HARDPOINTS[name], atol=1e-12)


def test_the_plant_has_every_load_point_of_the_arm():
    assert set(geo.BUILTIN.arm_points) == set(la.HARDPOINTS)
    # the arm frame of the plant is cosim.lower_arm's: origin ARM_ORIGIN, axes parallel
    o, R = (geo.BUILTIN.arm_origin, geo.BUILTIN.arm_rotation)
    assert np.allclose(o, la.ARM_ORIGIN) and np.allclose(R, np.eye(3))


@pytest.fixture(scope="module")
def corner():
    m = dw.DoubleWishboneCorner()
    yield m
    m.close()


def test_pybullet_places_the_arm_where_cosim_lower_arm_says(corner):
    c, b = corner.client, corner.body
    arm = p.getLinkState(b, dw.LOWER_ARM, computeForwardKinematics=1, physicsClientId=c)
    hub = p.getLinkState(b, dw.HUB, computeForwardKinematics=1, physicsClientId=c)
    # the body starts at z = 0 of the world = the static corner frame
    assert np.allclose(arm[4], la.ARM_ORIGIN, atol=1e-9)          # pivot-axis midpoint
    assert np.allclose(hub[4], la.to_corner(la.BALL_JOINT), atol=1e-9)  # hub on the ball joint
    assert np.allclose(hub[0], geo.BUILTIN.wheel_centre, atol=1e-9)          # hub mass at the wheel
    info = corner.info()
    for name, pt in la.HARDPOINTS.items():
        assert np.allclose(info["arm_points"][name], pt, atol=1e-12), name
    # the damper's lower mount and the pad ride on the arm at the arm's points
    assert np.allclose(corner._bot, la.to_corner(la.DAMPER_MOUNT), atol=1e-6)
    assert np.allclose(corner._pad, la.to_corner(la.BUMP_STOP_PAD), atol=1e-6)


def test_spring_force_uses_the_ball_joint_lever():
    m = dw.DoubleWishboneCorner()
    try:
        W = m.static_tyre_load()
        for _ in range(200):  # push the wheel up: 2 kN more tyre load
            m.substep(1e-3, W + 2000.0, 3800.0 * m.state()["v_damper"])
        dtheta = float(m.state()["arm_angle"][0])
        F_s = float(m.spring_force()[0])
    finally:
        m.close()
    assert dtheta > 0.01
    assert F_s == pytest.approx(m.params.k_theta * dtheta / 0.294, rel=1e-9)
    assert la.lever_ball_joint() == 0.294
