"""`python -m harness validate LOG --robot URDF --out DIR`: the torque prediction error
of a URDF on a log, per joint and pooled, and clear errors for bad input."""
from __future__ import annotations

import json

import numpy as np
import pytest
from robot_helpers import FRICTION, multisine_log, payload_link

from harness.cli import main
from harness.robot.examples import example_urdf
from harness.robot.urdf import read_urdf
from harness.robot.validate import write_validation


@pytest.fixture(scope="module")
def arm():
    path, _ = example_urdf("double_pendulum")
    return path, read_urdf(path)


def _log(path, truth, seconds: float = 8.0):
    t, q, _, _, tau = multisine_log(truth, seconds, 1e-3)
    np.savetxt(path, np.column_stack([t, q, tau]), delimiter=",", header="t,q1,q2,u1,u2",
               comments="", fmt="%.17g")
    return path


def test_the_true_model_predicts_and_a_wrong_one_does_not(tmp_path, arm, capsys):
    urdf, robot = arm
    truth = robot.rigid_body(link=payload_link(robot.arrays()["link"]), friction=FRICTION)
    data = _log(tmp_path / "log.csv", truth)
    # the URDF without the payload and friction: a wrong model
    assert main(["validate", str(data), "--robot", str(urdf), "--out", str(tmp_path / "v")]) == 0
    report = json.loads((tmp_path / "v" / "validation.json").read_text())
    wrong = report["relative_error"]["pooled"]
    assert set(report["relative_error"]["per_joint"]) == set(robot.joint_names)
    assert 0.3 < wrong < 1.0, wrong  # measured 0.61
    assert (tmp_path / "v" / "validation.png").stat().st_size > 1000
    assert "pooled" in capsys.readouterr().out
    # the true parameters written as a URDF: the model's Coulomb steps pass the filter
    # the measured torque passed, so only the filter's rounding is left (measured 9e-7;
    # 1.8 % when the steps were compared unfiltered)
    from harness.robot.consistency import write_identified_urdf
    pi = np.concatenate([payload_link(robot.arrays()["link"]).ravel(), FRICTION.ravel()])
    true_urdf = tmp_path / "true.urdf"
    write_identified_urdf(robot, pi, true_urdf, "the true arm")
    assert main(["validate", str(data), "--robot", str(true_urdf),
                 "--out", str(tmp_path / "t")]) == 0
    right = json.loads((tmp_path / "t" / "validation.json").read_text())
    assert right["relative_error"]["pooled"] < 1e-5


def test_a_coarse_encoder_is_scored_over_a_longer_window(tmp_path, arm):
    """Without --window, validate smooths a coarse encoder's steps over the window
    identify would choose, so they are not scored as the model's torque error."""
    urdf, robot = arm
    truth = robot.rigid_body(link=payload_link(robot.arrays()["link"]), friction=FRICTION)
    from harness.robot.consistency import write_identified_urdf
    pi = np.concatenate([payload_link(robot.arrays()["link"]).ravel(), FRICTION.ravel()])
    write_identified_urdf(robot, pi, tmp_path / "true.urdf", "the true arm")
    t, q, _, _, tau = multisine_log(truth, 20.0, 1 / 200)
    data = tmp_path / "coarse.csv"
    np.savetxt(data, np.column_stack([t, np.round(q / 0.01) * 0.01, tau]), delimiter=",",
               header="t,q1,q2,u1,u2", comments="", fmt="%.17g")
    errors = {}
    for name, extra in (("chosen", []), ("fixed", ["--window", "0.05"])):
        assert main(["validate", str(data), "--robot", str(tmp_path / "true.urdf"),
                     "--out", str(tmp_path / name), *extra]) == 0
        errors[name] = json.loads((tmp_path / name / "validation.json").read_text())
    assert errors["chosen"]["window"] >= 0.15
    # measured: 0.295 s, 1.8 % against 0.05 s, 124 %
    assert (errors["chosen"]["relative_error"]["pooled"]
            < 0.2 * errors["fixed"]["relative_error"]["pooled"])


@pytest.mark.parametrize("arguments, message", [
    (["--robot", "missing.urdf"], "missing.urdf"),
    (["--robot", "URDF", "--columns", "q1"], "is not ROLE=COLUMN"),
    (["--model", "m.toml", "--lock", "j"], "go with --robot"),
])
def test_bad_input_exits_2_naming_it(tmp_path, arm, capsys, arguments, message):
    urdf, robot = arm
    data = _log(tmp_path / "log.csv", robot.rigid_body(), seconds=1.0)
    arguments = [str(urdf) if a == "URDF" else a for a in arguments]
    assert main(["validate", str(data), *arguments, "--out", str(tmp_path / "o")]) == 2
    assert message in capsys.readouterr().err


def test_the_report_names_its_definition(tmp_path):
    t = np.linspace(0, 1, 11)
    u = np.ones((11, 1))
    write_validation(tmp_path, "r.urdf", "l.csv", 0.05, t, u, 1.1 * u, {"j": 0.1}, 0.1)
    report = json.loads((tmp_path / "validation.json").read_text())
    assert report["relative_error"] == {"per_joint": {"j": 0.1}, "pooled": 0.1}
    assert "RMS of (predicted - measured torque)" in report["definition"]
