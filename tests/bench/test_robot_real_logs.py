"""bench/reports/robot_real_logs.py's arms with drive inertias and torque offsets (cases e
to f3): their truth adds Ia_i q_i'' and a constant offset to the other cases' robot."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bench.reports import robot_real_logs as report
from harness.robot.examples import example_urdf
from harness.robot.urdf import read_urdf


def test_case_keys_and_twins():
    keys = [case.key for case in report.CASES]
    assert len(keys) == len(set(keys))
    by_key = {case.key: case for case in report.CASES}
    for key, robot, joints in (("e", "ur5", 6), ("f", "panda", 7)):
        case, twin = by_key[key], by_key[key + "2"]
        assert case.drive and case.robot == robot and len(case.gains or ()) == joints
        # the case names the URDF's joint model, its twin takes identify's default
        assert case.joint_terms == "none" and twin.joint_terms is None
        assert twin.logs_from == key
        # the twin reuses the logs: every property that makes them is the same
        assert dataclasses.replace(twin, key=key, describe=case.describe, joint_terms="none",
                                   logs_from=None) == case
        assert keys.index(key) < keys.index(key + "2")
        # the third twin: the default model class, the centres of mass in the geometry
        third = by_key[key + "3"]
        assert third.com_in_geometry and not twin.com_in_geometry
        assert dataclasses.replace(third, key=twin.key, describe=twin.describe,
                                   com_in_geometry=False) == twin
        assert keys.index(key) < keys.index(key + "3")


@pytest.mark.parametrize("key", ["e", "f"])
def test_drive_truth_adds_armature_and_offset(key):
    case = next(c for c in report.CASES if c.key == key)
    path, locked = example_urdf(case.robot)
    robot = read_urdf(path, locked=locked)
    forward, extra = report._truth(case, robot, path, locked)
    plain, plain_extra = report._truth(dataclasses.replace(case, drive=False), robot, path,
                                       locked)
    armature, offset = np.asarray(extra["armature"]), np.asarray(extra["torque_offset"])
    assert extra["true_masses"] == plain_extra["true_masses"]  # the same links
    assert np.all(armature > 0) and np.all(offset != 0)
    rng = np.random.default_rng(5)
    for _ in range(5):
        q, qd, tau = (rng.uniform(-a, a, robot.n) for a in (np.pi, 2.0, 20.0))
        qdd = forward(q, qd, tau)
        # the rigid body without the drive sees the torque less Ia q'' and the offset
        assert np.allclose(plain(q, qd, tau - armature * qdd - offset), qdd,
                           rtol=1e-9, atol=1e-9)
