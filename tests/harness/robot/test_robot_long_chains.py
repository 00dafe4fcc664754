"""Chains longer than the RobotObserver FMU's 7 joints: identify --robot takes them (the
native library's core is compiled for 12), robot-fmu-parameters refuses them by name."""
from __future__ import annotations

import json

import fmpy
import numpy as np
import pytest
from robot_helpers import random_chain_urdf

from harness.cli import main
from harness.paths import default_fmu_dir
from harness.robot.fmu import FMU_MAX_JOINTS
from harness.robot.layout import ParameterLayout
from harness.robot.native import core_defaults
from harness.robot.urdf import read_urdf

JOINTS = 9


@pytest.fixture(scope="module")
def nine_joints(tmp_path_factory):
    """A random 9-joint chain (revolute and prismatic joints, arbitrary axes) and a 6 s log
    of it at 1 kHz along a multi-sine, its torques by the URDF's inverse dynamics."""
    folder = tmp_path_factory.mktemp("long_chain")
    rng = np.random.default_rng(9)
    kinds = ["revolute", "revolute", "prismatic"] * 3
    urdf = folder / "chain.urdf"
    urdf.write_text(random_chain_urdf(rng, kinds, fixed_between=False))
    robot = read_urdf(urdf)
    t = np.arange(0.0, 6.0, 1e-3)
    f = np.array([0.3, 0.7, 1.1, 1.7])
    phase = rng.uniform(0, 2 * np.pi, (JOINTS, 4))
    amplitude = np.where(np.array(kinds) == "prismatic", 0.05, 0.4)[:, None] / np.sqrt(f)
    angle = 2 * np.pi * f * t[:, None, None] + phase
    w = 2 * np.pi * f
    q = (amplitude * np.sin(angle)).sum(-1)
    qd = (amplitude * w * np.cos(angle)).sum(-1)
    qdd = -(amplitude * w ** 2 * np.sin(angle)).sum(-1)
    tau = robot.rigid_body().inverse_dynamics(q, qd, qdd)
    log = folder / "log.csv"
    header = ["t", *(f"q{i + 1}" for i in range(JOINTS)), *(f"u{i + 1}" for i in range(JOINTS))]
    np.savetxt(log, np.column_stack([t, q, tau]), delimiter=",", header=",".join(header),
               comments="")
    return robot, urdf, log, folder


def test_the_offline_path_takes_nine_joints(nine_joints):
    """identify --robot on exact data: exit 0; the base parameters (68 of 108 standard
    ones here) are the URDF's, which made the log, within 1e-3 of the largest (measured
    1.2e-4), and the estimate predicts the log's torques within 0.1 %."""
    robot, urdf, log, folder = nine_joints
    assert robot.n == JOINTS <= core_defaults().max_joints
    out = folder / "out"
    assert main(["identify", str(log), "--robot", str(urdf), "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["joints"] == robot.joint_names
    table = np.genfromtxt(out / "parameters.csv", delimiter=",", names=True, dtype=None,
                          encoding="utf-8")
    assert len(table) == summary["base_parameters"] < ParameterLayout(JOINTS).size
    scale = np.abs(table["urdf"]).max()
    assert np.abs(table["estimate"] - table["urdf"]).max() <= 1e-3 * scale
    assert summary["training_prediction"]["estimate"]["pooled"] < 1e-3


def test_the_fmu_parameters_refuse_more_joints_than_the_fmu_holds(nine_joints, capsys):
    _, urdf, _, folder = nine_joints
    out = folder / "robot.ssv"
    assert main(["robot-fmu-parameters", str(urdf), "--out", str(out)]) == 2
    assert "9 moving joints; the RobotObserver FMU holds at most 7" in capsys.readouterr().err
    assert not out.exists()


def test_the_fmus_joint_count_is_the_one_refused_beyond():
    """FMU_MAX_JOINTS is the RobotObserver FMU's row count of its joint arrays."""
    description = fmpy.read_model_description(str(default_fmu_dir() / "RobotObserver.fmu"))
    rows = [v.name for v in description.modelVariables if v.name.startswith("q[")]
    assert len(rows) == FMU_MAX_JOINTS
