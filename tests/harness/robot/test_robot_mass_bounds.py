"""--mass-range and --total-mass: what the user knows of the masses holds the physically
consistent model (a two-link arm with a payload whose log is noise-free)."""
from __future__ import annotations

import json

import numpy as np
import pytest
from robot_helpers import multisine_log, payload_link

from harness.cli import main
from harness.robot.examples import example_urdf
from harness.robot.urdf import read_urdf


@pytest.fixture(scope="module")
def arm(tmp_path_factory):
    path, _ = example_urdf("double_pendulum")
    robot = read_urdf(path)
    truth = robot.rigid_body(link=payload_link(robot.arrays()["link"]))
    t, q, _, _, tau = multisine_log(truth, 10.0, 1e-3)
    resolution = 2 * np.pi / 2 ** 17
    data = tmp_path_factory.mktemp("bounds") / "log.csv"
    np.savetxt(data, np.column_stack([t, np.round(q / resolution) * resolution, tau]),
               delimiter=",", header="t,q1,q2,u1,u2", comments="", fmt="%.17g")
    return path, robot, data


def identify(arm, out, *options: str) -> tuple[int, dict]:
    """identify --robot's exit status (argparse's too) and its summary.json ({}: none)."""
    path, _, data = arm
    try:
        code = main(["identify", str(data), "--robot", str(path), "--joint-terms", "none",
                     "--out", str(out), *options])
    except SystemExit as stop:
        code = int(stop.code or 0)
    summary = out / "summary.json"
    return code, json.loads(summary.read_text()) if summary.exists() else {}


def test_a_mass_range_and_the_total_mass_hold_the_consistent_model(arm, tmp_path):
    _, robot, _ = arm
    links = [joint.child_link for joint in robot.joints]
    code, free = identify(arm, tmp_path / "free")
    assert code in (0, 1)
    first = free["masses"][links[0]]
    # link 1's mass is one the two-link arm's motion leaves to the prior: any range holds it
    low, high = 1.3 * first, 1.5 * first
    code, held = identify(arm, tmp_path / "range", "--mass-range", f"{links[0]}={low}:{high}")
    assert code in (0, 1)
    assert low * (1 - 1e-6) <= held["masses"][links[0]] <= high * (1 + 1e-6)
    assert held["mass_bounds"] == {"ranges": {links[0]: [low, high]}, "total_mass": None,
                                   "com_boxes": {}, "without_com_box": {}}
    total = 1.1 * sum(free["masses"].values())
    code, summed = identify(arm, tmp_path / "total", "--total-mass", str(total))
    assert code in (0, 1)
    assert sum(summed["masses"].values()) == pytest.approx(total, rel=1e-6)
    assert free["mass_bounds"] is None


def test_bounds_no_consistent_model_meets_are_refused_by_name(arm, tmp_path, capsys):
    _, robot, _ = arm
    links = [joint.child_link for joint in robot.joints]
    code, _ = identify(arm, tmp_path / "sum", "--mass-range", f"{links[0]}=1:2",
                       "--mass-range", f"{links[1]}=1:2", "--total-mass", "10")
    assert code == 2
    assert "--total-mass 10 kg cannot be met within the --mass-range bounds (together 2 to " \
        "4 kg)" in capsys.readouterr().err
    assert not (tmp_path / "sum" / "summary.json").exists()


def test_a_range_the_data_contradict_is_met_and_said(arm, tmp_path):
    """link 2 carries the payload the torques weigh: held to at most 1 mg, the consistent
    model predicts the log worse than the URDF, identify warns and keeps the URDF (exit 1)."""
    _, robot, _ = arm
    code, summary = identify(arm, tmp_path / "data", "--mass-range",
                             f"{robot.joints[1].child_link}=0:1e-6")
    assert code == 1
    assert summary["identified_urdf_holds"] == "urdf"
    assert any("predicts the training log worse than the URDF" in warning
               for warning in summary["warnings"])


@pytest.mark.parametrize("options, message", [
    (["--mass-range", "link9=1:2"], "not one of the chain's bodies"),
    (["--mass-range", "link1=2:1"], "0 <= LOW <= HIGH"),
    (["--mass-range", "link1=1"], "expected LINK=LOW:HIGH"),
    (["--mass-range", "link1=a:2"], "is not a number"),
    (["--mass-range", "link1=1:2", "--mass-range", "link1=1:3"], "given twice"),
    (["--total-mass", "0"], "--total-mass"),
])
def test_bad_mass_bounds_exit_2_naming_them(arm, tmp_path, capsys, options, message):
    code, _ = identify(arm, tmp_path / "out", *options)
    assert code == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize("option", [["--total-mass", "3"], ["--com-in-geometry"]])
def test_mass_bounds_need_robot(tmp_path, capsys, option):
    data = tmp_path / "log.csv"
    data.write_text("t,y,u\n0,0,0\n")
    assert main(["identify", str(data), *option, "--out", str(tmp_path / "o")]) == 2
    assert option[0] in capsys.readouterr().err
