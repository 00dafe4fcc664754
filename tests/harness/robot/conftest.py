"""Fixtures of the robot tests; the shared helpers are in robot_helpers.py (imported by
name: a module named conftest is shadowed by the other test folders' conftest)."""
from __future__ import annotations

import pytest

from harness.robot.examples import example_urdf


@pytest.fixture(params=["ur5", "panda", "double_pendulum"])
def example(request):
    """(name, URDF path, locked joints) of each example robot."""
    path, locked = example_urdf(request.param)
    return request.param, path, locked
