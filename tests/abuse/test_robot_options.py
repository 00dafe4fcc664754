"""Options of the robot commands: every number finite and in its range (exit status
2 naming the option, nothing written), and identify's options for a t, y, u log
refused with --robot instead of silently ignored (but --time-unit, which the robot
path honours: tests/abuse/test_robot_logs.py)."""
from __future__ import annotations

from pathlib import Path

import pytest
from cli_runner import cli, refused

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
