"""Shared fixtures of the vehicle tests."""

import pytest

from ._sim import big_bump_run


@pytest.fixture(scope="session")
def big_bump():
    """The realistic corner over a 100 mm x 1.0 m bump at 34 km/h, bumper fitted, 0.5 ms
    substeps (records of :func:`._sim.big_bump_run`)."""
    return big_bump_run(True)
