"""Options of the robot commands: every number finite and in its range (exit status
2 naming the option, nothing written), and identify's options for a t, y, u log
refused with --robot instead of silently ignored (but --time-unit, which the robot
path honours: tests/harness/robot/test_robot_joint_log_input.py).

Drive gains and units beyond their range are refused by name; identify --robot exits
with status 1 after its warnings (harness/robot/cli.py).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from cli_runner import cli, refused
from robot_helpers import swing_log

from harness.robot.examples import example_urdf
from harness.robot.urdf import read_urdf

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


@pytest.fixture(scope="module")
def urdf() -> Path:
    from harness.robot.examples import example_urdf
    return Path(example_urdf("double_pendulum")[0])


@pytest.mark.parametrize("option, value", [
    ("--step", "nan"), ("--step", "-1"), ("--step", "0"), ("--step", "1e308"),
    ("--step", "inf"), ("--f-plus", "nan"), ("--f-plus", "-1"), ("--f-plus", "inf"),
    ("--coulomb-velocity", "-5"), ("--coulomb-velocity", "nan"),
    ("--coulomb-velocity", "inf"), ("--min-speed", "inf"), ("--reversal-margin", "nan"),
    ("--reversal-margin", "inf"),
])
def test_robot_fmu_parameters_refuses_bad_numbers(tmp_path, urdf, option, value):
    out = tmp_path / "robot.ssv"
    code, text = cli(["robot-fmu-parameters", str(urdf), "--out", str(out), option, value])
    assert code == 2, text
    refused(code, text, option)
    assert not out.exists()


@pytest.mark.parametrize("value", ["nan", "-1", "inf", "0"])
def test_identify_robot_refuses_a_bad_window(tmp_path, urdf, value):
    out = tmp_path / "out"
    code, text = cli(["identify", str(tmp_path / "log.csv"), "--robot", str(urdf),
                      "--out", str(out), "--window", value])
    assert code == 2, text
    refused(code, text, "--window")
    assert not out.exists()


@pytest.mark.parametrize("options", [
    ["--resample"], ["--resample", "0.001"],
    ["--time-tolerance", "0.5"], ["--format", "parquet"], ["--param", "h=0.001"],
    ["--identifier", "mff"], ["--input-hold", "sampled"], ["--csv-decimation", "10"],
])
def test_identify_robot_refuses_the_options_it_does_not_use(tmp_path, urdf, options):
    out = tmp_path / "out"
    code, text = cli(["identify", str(tmp_path / "log.csv"), "--robot", str(urdf),
                      "--out", str(out), *options])
    assert code == 2, text
    refused(code, text, options[0], "--robot")
    assert not out.exists()


def swing(path: Path) -> Path:
    t = 1e-3 * np.arange(4000)
    q = np.column_stack([0.8 * np.sin(1.3 * t), 0.6 * np.sin(2.1 * t)])
    u = np.column_stack([5.0 * np.sin(1.3 * t), 2.0 * np.cos(2.1 * t)])
    np.savetxt(path, np.column_stack([t, q, u]), delimiter=",", header="t,q1,q2,u1,u2",
               comments="", fmt="%.17g")
    return path


@pytest.mark.parametrize("command", ["identify", "validate"])
@pytest.mark.parametrize("gains, word", [("1e300,1", "1e300"), ("1,1e-300", "1e-300")])
def test_drive_gains_beyond_the_range_are_refused(tmp_path, urdf, command, gains, word):
    code, text = cli([command, str(swing(tmp_path / "log.csv")), "--robot", str(urdf),
                      "--torque-gains", gains, "--out", str(tmp_path / "out")])
    assert code == 2, text
    refused(code, text, "--torque-gains", word)


@pytest.fixture(scope="module")
def arm():
    path, _ = example_urdf("double_pendulum")
    return path, read_urdf(path)


@pytest.mark.parametrize("command", ["identify", "validate"])
@pytest.mark.parametrize("options, words", [
    (["--torque-gains", "1,2,3"], ["--torque-gains", "3 gain(s) for a robot of 2 joints"]),
    (["--torque-gains", "1"], ["--torque-gains", "1 gain(s) for a robot of 2 joints"]),
    (["--torque-gains", "1,0"], ["--torque-gains", "gain 2 ('0')", "other than 0"]),
    (["--torque-gains=-1e-9,2"], ["--torque-gains", "gain 1 ('-1e-9')", "+-1e-06"]),
    (["--torque-gains", "1,nan"], ["--torque-gains", "gain 2 ('nan')"]),
    (["--torque-gains", "1,inf"], ["--torque-gains", "gain 2 ('inf')"]),
    (["--torque-gains", "1,amps"], ["--torque-gains", "gain 2 ('amps')"]),
    (["--torque-gains", "1,,2"], ["--torque-gains", "gain 2 is empty"]),
    (["--angle-unit", "grad"], ["--angle-unit", "grad"]),
    (["--time-unit", "h"], ["--time-unit", "'h'"]),
    (["--length-unit", "mm"], ["--length-unit mm", "no prismatic joint"]),
])
def test_bad_units_and_gains_exit_2_naming_them(tmp_path, arm, command, options, words):
    from cli_runner import cli, refused
    urdf, _ = arm
    data = swing_log(tmp_path / "log.csv", np.arange(6000) * 1e-3)
    out = tmp_path / "out"
    code, text = cli([command, str(data), "--robot", str(urdf), "--out", str(out), *options])
    assert code == 2, text
    refused(code, text, *words)
    assert not out.exists()


def test_identify_robot_exits_1_after_its_warnings(tmp_path, monkeypatch):
    """A result with warnings (the identified model predicts worse than the URDF) is
    written, said, and exits 1 as docs/cli.md says."""
    from harness.robot.examples import example_urdf
    from harness.robot.pipeline import Identification
    urdf, _ = example_urdf("double_pendulum")
    t = np.arange(6000) * 1e-3
    q = np.column_stack([0.8 * np.sin(1.3 * t), 0.6 * np.sin(2.1 * t)])
    u = np.column_stack([5.0 * np.sin(1.3 * t), 2.0 * np.cos(2.1 * t)])
    np.savetxt(tmp_path / "log.csv", np.column_stack([t, q, u]), delimiter=",",
               header="t,q1,q2,u1,u2", comments="", fmt="%.17g")
    monkeypatch.setattr(Identification, "warnings",
                        property(lambda self: ["the identified model predicts worse"]))
    code, text = cli(["identify", str(tmp_path / "log.csv"), "--robot", str(urdf), "--out",
                      str(tmp_path / "out"), "--unknown", "payload"])
    assert code == 1, text
    assert "the identified model predicts worse" in text


@pytest.mark.parametrize("options", [["--angle-unit", "deg"], ["--length-unit", "mm"],
                                     ["--torque-gains", "1,2"], ["--lock", "j1"]])
def test_robot_unit_options_without_robot_are_refused(tmp_path, options):
    data = swing_log(tmp_path / "log.csv", np.arange(6000) * 1e-3)
    code, text = cli(["identify", str(data), "--out", str(tmp_path / "o"), *options])
    assert code == 2, text
    refused(code, text, options[0], "--robot")
    code, text = cli(["identify", str(data), "--model", "m.toml", "--out", str(tmp_path / "o"),
                      *options])
    assert code == 2, text
    refused(code, text, options[0], "--model", "[units]")
    code, text = cli(["validate", str(data), "--model", "m.toml", "--out", str(tmp_path / "o"),
                      *options])
    assert code == 2, text
    refused(code, text, options[0], "go with --robot", "[units]")
    assert not (tmp_path / "o").exists()
