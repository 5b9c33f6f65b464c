"""The plant's lower-arm load points agree with the fatigue worker's arm geometry."""

import numpy as np
import pytest

from nodes.plant.double_wishbone import ARM_POINTS, to_arm_frame

geom = pytest.importorskip("nodes.fatigue.arm_geometry")


@pytest.mark.parametrize("name,const", [("bush_front", "BUSH_FRONT"),
                                        ("bush_rear", "BUSH_REAR"),
                                        ("ball_joint", "BALL_JOINT"),
                                        ("damper_mount", "DAMPER_MOUNT")])
def test_points_agree(name, const):
    assert np.allclose(to_arm_frame(ARM_POINTS[name]), np.asarray(getattr(geom, const)),
                       atol=1e-6)
