"""`python -m harness identify DATA.csv --robot ROBOT.urdf`: a two-link arm with an
unknown tip payload, logged by 17-bit encoders, and the errors for bad input."""
from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin
import pytest
from robot_helpers import FRICTION, PAYLOAD, multisine_log, payload_link

from harness.cli import main
from harness.robot.examples import example_urdf
from harness.robot.urdf import read_urdf


def write_log(path, robot, seconds: float = 12.0, h: float = 1e-3, bits: int = 17):
    """Torques of the true arm along an analytic multi-sine (no integration error)."""
    t, q, _, _, tau = multisine_log(robot.rigid_body(link=payload_link(robot.arrays()["link"]),
                                                     friction=FRICTION), seconds, h)
    resolution = 2 * np.pi / 2 ** bits
    q = np.round(q / resolution) * resolution
    np.savetxt(path, np.column_stack([t, q, tau]), delimiter=",", header="t,q1,q2,u1,u2",
               comments="")
    return path


@pytest.fixture(scope="module")
def arm():
    path, _ = example_urdf("double_pendulum")
    return path, read_urdf(path)


def test_payload_and_friction_from_17_bit_encoders(tmp_path, arm):
    urdf, robot = arm
    data = write_log(tmp_path / "arm.csv", robot)
    out = tmp_path / "out"
    assert main(["identify", str(data), "--robot", str(urdf), "--unknown", "payload",
                 "--out", str(out)]) == 0
    for name in ["velocities.csv", "parameters.csv", "identified.urdf", "summary.json",
                 "velocities.png"]:
        assert (out / name).stat().st_size > 0
    identified = read_urdf(out / "identified.urdf")  # validates: physically consistent
    nominal_mass = robot.arrays()["link"][1, 0]
    mass = identified.arrays()["link"][1, 0]
    assert abs(mass - nominal_mass - PAYLOAD) / PAYLOAD < 0.005
    friction = identified.arrays()["friction"]
    assert np.all(np.abs(friction - FRICTION) / FRICTION < 0.03), friction
    # Pinocchio reads it too, with the identified joint damping
    model = pin.buildModelFromUrdf(str(out / "identified.urdf"))
    assert np.allclose(model.damping, friction[:, 0])
    velocity = np.loadtxt(out / "velocities.csv", delimiter=",", skiprows=1)
    assert velocity.shape[1] == 3


def test_the_observer_velocities(tmp_path, arm):
    urdf, robot = arm
    data = write_log(tmp_path / "arm.csv", robot, seconds=6.0, bits=30)
    out = tmp_path / "out"
    assert main(["identify", str(data), "--robot", str(urdf), "--unknown", "payload",
                 "--velocity", "observer", "--out", str(out)]) == 0
    identified = read_urdf(out / "identified.urdf")
    mass = identified.arrays()["link"][1, 0] - robot.arrays()["link"][1, 0]
    assert abs(mass - PAYLOAD) / PAYLOAD < 0.05


def _nan_time(lines: list[str]) -> list[str]:
    lines[2] = "nan," + lines[2].split(",", 1)[1]
    return lines


def _one_position_column(lines: list[str]) -> list[str]:
    return ["t,q1,u1,u2,x"] + lines[1:]


def _three_position_columns(lines: list[str]) -> list[str]:
    return [lines[0] + ",q3"] + [line + ",0" for line in lines[1:]]


@pytest.mark.parametrize("change, message", [
    (_nan_time, "line 3: t is NaN"),
    (_one_position_column, "no column 'q2'"),
    (_three_position_columns, "3 position columns for a robot of 2 joints"),
])
def test_bad_logs(tmp_path, arm, capsys, change, message):
    urdf, robot = arm
    data = write_log(tmp_path / "arm.csv", robot, seconds=1.0)
    data.write_text("\n".join(change(data.read_text().strip().split("\n"))) + "\n")
    assert main(["identify", str(data), "--robot", str(urdf), "--out", str(tmp_path / "o")]) == 2
    assert message in capsys.readouterr().err


def test_bad_urdf(tmp_path, arm, capsys):
    urdf, robot = arm
    data = write_log(tmp_path / "arm.csv", robot, seconds=1.0)
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot><link name='a'>")
    assert main(["identify", str(data), "--robot", str(bad), "--out", str(tmp_path / "o")]) == 2
    assert "does not parse as XML" in capsys.readouterr().err


def test_a_negative_min_speed_is_refused(tmp_path, arm, capsys):
    urdf, robot = arm
    data = write_log(tmp_path / "arm.csv", robot, seconds=1.0)
    with pytest.raises(SystemExit) as exit_:
        main(["identify", str(data), "--robot", str(urdf), "--min-speed", "-1",
              "--out", str(tmp_path / "o")])
    assert exit_.value.code == 2
    assert "--min-speed: '-1' is not a number >= 0" in capsys.readouterr().err


def _slow_joint_log(robot, peak_speed: float, seconds: float = 3.0, h: float = 1e-3):
    """Joint 1 along the helpers' multi-sine, joint 2 a sine of `peak_speed` rad/s at
    0.5 Hz: joint 2 is above a min_speed v a share 1 - 2 arcsin(v / peak) / pi of the time."""
    from harness.robot.joint_log import JointLog
    truth = robot.rigid_body(link=payload_link(robot.arrays()["link"]), friction=FRICTION)
    t, q, qd, qdd, _ = multisine_log(truth, seconds, h)
    w = 2 * np.pi * 0.5
    q[:, 1] = peak_speed / w * np.sin(w * t)
    qd[:, 1] = peak_speed * np.cos(w * t)
    qdd[:, 1] = -peak_speed * w * np.sin(w * t)
    return JointLog(t, q, truth.inverse_dynamics(q, qd, qdd))


def test_a_joint_that_never_reaches_min_speed_is_named(arm):
    """Joint 2 never exceeds 0.04 rad/s: with min_speed 0.05 it would lose every friction
    equation; the error names it and the remedy."""
    from harness.robot.joint_log import LogError
    from harness.robot.pipeline import identify_robot
    _, robot = arm
    log = _slow_joint_log(robot, 0.04)
    with pytest.raises(LogError, match=r"joint 'joint2' keeps 0\.0 % of its equations.*"
                                       r"lower --min-speed"):
        identify_robot(robot, log, unknown="payload")
    # the remedy works, and joint 1 was never the problem
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        identify_robot(robot, log, unknown="payload", min_speed=0.01)


def test_a_joint_that_rarely_reaches_min_speed_is_a_warning(arm):
    """Joint 2 above 0.05 rad/s in about 6 % of the samples (peak 0.0502 rad/s): a warning
    naming it, and the identification still runs."""
    from harness.robot.pipeline import identify_robot
    _, robot = arm
    with pytest.warns(UserWarning, match=r"joint 'joint2' keeps [0-9.]+ % .*--min-speed"):
        identify_robot(robot, _slow_joint_log(robot, 0.0502), unknown="payload")
