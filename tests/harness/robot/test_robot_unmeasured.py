"""A joint whose torque the log does not hold (--unmeasured): its equation is left out of
the fit and of the scores, its dynamics stay in the other joints' equations."""
from __future__ import annotations

import csv
import json

import numpy as np
import pandas as pd
import pytest
from robot_helpers import FRICTION, multisine_log, payload_link

from harness.cli import main
from harness.robot.examples import example_urdf
from harness.robot.urdf import read_urdf


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The double pendulum with a payload and friction, 8 s at 1 kHz: identified from both
    torques, and from joint 1's alone (no u2 column, --unmeasured joint2)."""
    folder = tmp_path_factory.mktemp("unmeasured")
    path, _ = example_urdf("double_pendulum")
    robot = read_urdf(path)
    truth = robot.rigid_body(link=payload_link(robot.arrays()["link"]), friction=FRICTION)
    t, q, _, _, tau = multisine_log(truth, 8.0, 1e-3)
    frame = pd.DataFrame({"t": t, "q1": q[:, 0], "q2": q[:, 1], "u1": tau[:, 0],
                          "u2": tau[:, 1]})
    frame.to_csv(folder / "both.csv", index=False, float_format="%.17g")
    frame.drop(columns="u2").to_csv(folder / "one.csv", index=False, float_format="%.17g")
    codes = {
        "both": main(["identify", str(folder / "both.csv"), "--robot", str(path), "--out",
                      str(folder / "both")]),
        "one": main(["identify", str(folder / "one.csv"), "--robot", str(path), "--out",
                     str(folder / "one"), "--unmeasured", "joint2"]),
        "validate": main(["validate", str(folder / "one.csv"), "--robot",
                          str(folder / "one" / "identified.urdf"), "--out",
                          str(folder / "validation"), "--unmeasured", "joint2"])}
    return folder, codes


def _parameters(folder) -> dict[str, tuple[float, float]]:
    with (folder / "parameters.csv").open() as handle:
        return {row["parameter"]: (float(row["estimate"]), float(row["std_error"]))
                for row in csv.DictReader(handle)}


def test_joint_1_alone_identifies_every_inertial_base_parameter(runs):
    """Joint 1's equation holds every inertial base parameter of this arm: from it alone
    they come out as from both joints (noise-free log: to 1e-5 of the largest; measured
    1.1e-6, joint 1's viscous friction)."""
    folder, codes = runs
    assert codes["both"] == 0 and codes["one"] == 0
    both, one = _parameters(folder / "both"), _parameters(folder / "one")
    assert list(both) == list(one)
    scale = max(abs(v) for v, _ in both.values())
    inertial = [name for name in both if not name.endswith((".fv", ".fc"))]
    assert len(inertial) == 6
    for name in [*inertial, "joint1.fv", "joint1.fc"]:
        assert abs(one[name][0] - both[name][0]) < 1e-5 * scale, name
        assert 0 < one[name][1] < 1e-6 * scale, name


def test_what_only_the_unmeasured_joint_holds_keeps_the_urdf_value(runs, capsys):
    """Its friction: the URDF's values with standard error 0 (nothing was fitted), said
    in the output and in summary.json; the command is not failed for it."""
    folder, _ = runs
    one = _parameters(folder / "one")
    urdf = read_urdf(example_urdf("double_pendulum")[0]).arrays()["friction"]
    assert one["joint2.fv"] == (pytest.approx(urdf[1, 0]), 0.0)
    assert one["joint2.fc"][1] == 0.0 and abs(one["joint2.fc"][0] - urdf[1, 1]) < 1e-12
    summary = json.loads((folder / "one" / "summary.json").read_text())
    assert summary["unmeasured_joints"] == ["joint2"] and summary["passive_joints"] == []
    assert summary["warnings"] == []
    assert np.isfinite(summary["condition_number"])


def test_validate_scores_the_measured_joints_only(runs):
    folder, codes = runs
    assert codes["validate"] == 0
    report = json.loads((folder / "validation" / "validation.json").read_text())
    assert report["unmeasured_joints"] == ["joint2"]
    assert report["relative_error"]["per_joint"]["joint2"] is None
    # the same figure (joint 2 adds nothing), summed in another order
    assert report["relative_error"]["pooled"] == pytest.approx(
        report["relative_error"]["per_joint"]["joint1"], rel=1e-12)
    assert report["relative_error"]["pooled"] < 1e-4


@pytest.mark.parametrize("options, words", [
    (["--unmeasured", "joint3"], ["--unmeasured", "'joint3' is not a moving joint",
                                  "joint1, joint2"]),
    (["--unmeasured", "joint2,joint2"], ["'joint2' is named twice"]),
    (["--unmeasured", "joint1,joint2"], ["no joint's torque would be left"]),
    (["--unmeasured", "joint2", "--columns", "u2=u1"], ["--columns names 'u2'",
                                                       "--unmeasured leaves out"]),
])
def test_bad_unmeasured_options_are_refused_by_name(runs, capsys, options, words):
    folder, _ = runs
    code = main(["identify", str(folder / "both.csv"), "--robot",
                 str(example_urdf("double_pendulum")[0]), "--out", str(folder / "bad"),
                 *options])
    text = capsys.readouterr().err
    assert code == 2 and "Traceback" not in text
    for word in words:
        assert word in text, (word, text)


def test_unmeasured_goes_with_robot_only(runs, capsys):
    folder, _ = runs
    model = folder / "m.toml"
    model.write_text('[model]\ncoordinates = ["q1"]\ninputs = ["u1"]\n'
                     'equations = ["J*der(q1,2) = u1"]\n[parameters]\nJ = { nominal = 1 }\n')
    code = main(["validate", str(folder / "both.csv"), "--model", str(model), "--out",
                 str(folder / "m"), "--unmeasured", "joint2"])
    assert code == 2 and "--unmeasured" in capsys.readouterr().err


def test_joint_terms_of_an_unmeasured_joint_are_held_not_refused(runs, capsys):
    """Its offset and Coulomb levels have no equation: held at 0 (not 'never moves
    forwards', the message for a measured joint that moves one way)."""
    folder, _ = runs
    out = folder / "terms"
    code = main(["identify", str(folder / "one.csv"), "--robot",
                 str(example_urdf("double_pendulum")[0]), "--out", str(out),
                 "--unmeasured", "joint2", "--joint-terms", "offset,asymmetric-coulomb"])
    assert code == 0, capsys.readouterr().err
    with (out / "joint_terms.csv").open() as handle:
        rows = {(r["joint"], r["term"]): float(r["value"]) for r in csv.DictReader(handle)}
    assert all(abs(v) < 1e-12 for (joint, _), v in rows.items() if joint == "joint2")
    assert rows[("joint1", "coulomb_positive")] > 0.1
