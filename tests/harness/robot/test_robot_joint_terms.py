"""The extra joint terms of `identify --robot` (offset, armature, asymmetric and smooth
Coulomb friction) and their sidecar joint_terms.csv in `validate --robot`: a two-link arm
with a tip payload whose drives have them, logged by 17-bit encoders."""
from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from robot_helpers import FRICTION, multisine_log, payload_link, swing_log

from harness.cli import main
from harness.robot.base_parameters import base_parameters, random_states
from harness.robot.examples import example_urdf
from harness.robot.joint_terms import JointTerms, JointTermsError, parse_terms, read_sidecar
from harness.robot.layout import ParameterLayout
from harness.robot.urdf import read_urdf

OFFSET = np.array([0.3, -0.2])          # N.m
ARMATURE = np.array([0.05, 0.02])       # kg.m^2
POSITIVE = np.array([0.25, 0.12])       # N.m, the Coulomb level moving forwards
NEGATIVE = np.array([0.15, 0.08])       # N.m, ... backwards
SMOOTH = 0.2                            # rad/s, tanh's velocity scale


@pytest.fixture(scope="module")
def arm():
    path, _ = example_urdf("double_pendulum")
    return path, read_urdf(path)


def drive_log(path, robot, offset=True, armature=True, asymmetric=True, smooth=False,
              seconds: float = 10.0, bits: int = 17, noise: float = 0.0):
    """The payload arm's torques with viscous friction FRICTION[:, 0] and the drive terms
    asked for (symmetric Coulomb FRICTION[:, 1] as sign(q'), or tanh(q'/SMOOTH) if smooth,
    unless asymmetric), and white noise of `noise` times each torque's RMS; positions
    rounded to `bits`-bit encoders."""
    friction = FRICTION.copy()
    friction[:, 1] = 0.0
    truth = robot.rigid_body(link=payload_link(robot.arrays()["link"]), friction=friction)
    t, q, qd, qdd, tau = multisine_log(truth, seconds, 1e-3)
    if asymmetric:
        tau = tau + POSITIVE * (qd > 0) - NEGATIVE * (qd < 0)
    else:
        tau = tau + FRICTION[:, 1] * (np.tanh(qd / SMOOTH) if smooth else np.sign(qd))
    tau = tau + (OFFSET if offset else 0.0) + (ARMATURE * qdd if armature else 0.0)
    rms = np.sqrt(np.mean(tau ** 2, axis=0))
    tau = tau + noise * rms * np.random.default_rng(7).normal(size=tau.shape)
    resolution = 2 * np.pi / 2 ** bits
    q = np.round(q / resolution) * resolution
    np.savetxt(path, np.column_stack([t, q, tau]), delimiter=",", header="t,q1,q2,u1,u2",
               comments="", fmt="%.17g")
    return path


def identify(tmp_path, urdf, data, name: str, *options: str) -> dict:
    """identify --robot --unknown payload: exit status 0, or 1 with its warnings
    (docs/cli.md), which summary.json lists."""
    out = tmp_path / name
    code = main(["identify", str(data), "--robot", str(urdf), "--unknown", "payload",
                 "--out", str(out), *options])
    summary = json.loads((out / "summary.json").read_text())
    assert code == (1 if summary["warnings"] else 0), (code, summary["warnings"])
    return summary


def sidecar_rows(path) -> dict[tuple[str, str], dict[str, str]]:
    with path.open(newline="") as handle:
        return {(row["joint"], row["term"]): row for row in csv.DictReader(handle)}


def consistent_error(summary: dict) -> float:
    return summary["training_prediction"]["consistent"]["pooled"]


def test_armature_and_the_two_coulomb_levels_are_recovered(tmp_path, arm):
    urdf, robot = arm
    data = drive_log(tmp_path / "log.csv", robot, offset=False)
    summary = identify(tmp_path, urdf, data, "on", "--joint-terms",
                       "armature,asymmetric-coulomb")
    names = robot.joint_names
    rows = sidecar_rows(tmp_path / "on" / "joint_terms.csv")
    for i, joint in enumerate(names):
        values = summary["joint_terms"]["values"][joint]
        for kind, truth in (("armature", ARMATURE), ("coulomb_positive", POSITIVE),
                            ("coulomb_negative", NEGATIVE)):
            assert abs(values[kind] - truth[i]) < 0.02 * truth[i], (joint, kind, values)
            row = rows[(joint, kind)]
            assert float(row["value"]) == pytest.approx(values[kind], rel=1e-8)
            assert float(row["std_error"]) < 0.01 * truth[i]
        assert rows[(joint, "armature")]["unit"] == "kg.m^2"
        assert rows[(joint, "coulomb_positive")]["unit"] == "N.m"
        # identified.urdf holds the mean Coulomb level, and the viscous friction
        assert summary["coulomb"][joint] == pytest.approx(
            0.5 * (values["coulomb_positive"] + values["coulomb_negative"]), rel=1e-9)
        assert abs(summary["viscous"][joint] - FRICTION[i, 0]) < 0.03 * FRICTION[i, 0]
    identified = read_urdf(tmp_path / "on" / "identified.urdf")
    assert np.allclose(identified.arrays()["friction"][:, 1],
                       [summary["coulomb"][j] for j in names], rtol=1e-9)
    # parameters.csv lists the terms among the base parameters
    with (tmp_path / "on" / "parameters.csv").open() as handle:
        listed = {row["parameter"] for row in csv.DictReader(handle)}
    assert {f"{j}.{k}" for j in names for k in ("armature", "coulomb_positive",
                                                 "coulomb_negative")} <= listed
    on = consistent_error(summary)
    off = consistent_error(identify(tmp_path, urdf, data, "off", "--joint-terms", "none"))
    assert on < 0.005 and off > 0.2, (on, off)   # measured 0.00035 and 0.29


def test_offsets_are_recovered_beside_the_symmetric_coulomb_friction(tmp_path, arm):
    urdf, robot = arm
    data = drive_log(tmp_path / "log.csv", robot, asymmetric=False)
    summary = identify(tmp_path, urdf, data, "on", "--joint-terms", "offset,armature")
    for i, joint in enumerate(robot.joint_names):
        values = summary["joint_terms"]["values"][joint]
        assert abs(values["offset"] - OFFSET[i]) < 0.02 * abs(OFFSET[i]), values
        assert abs(values["armature"] - ARMATURE[i]) < 0.02 * ARMATURE[i], values
        assert abs(summary["coulomb"][joint] - FRICTION[i, 1]) < 0.03 * FRICTION[i, 1]


def test_offset_and_asymmetric_coulomb_identify_two_combinations(tmp_path, arm):
    urdf, robot = arm
    data = drive_log(tmp_path / "log.csv", robot)
    summary = identify(tmp_path, urdf, data, "on", "--joint-terms",
                       "offset,armature,asymmetric-coulomb")
    with (tmp_path / "on" / "parameters.csv").open() as handle:
        described = {row["parameter"]: row["definition"] for row in csv.DictReader(handle)}
    for i, joint in enumerate(robot.joint_names):
        # the offset is folded into the Coulomb levels, and parameters.csv says so
        assert described[f"{joint}.coulomb_positive"] == (
            f"{joint}.coulomb_positive +1 {joint}.offset")
        assert described[f"{joint}.coulomb_negative"] == (
            f"{joint}.coulomb_negative -1 {joint}.offset")
        assert f"{joint}.offset" not in described
        values = summary["joint_terms"]["values"][joint]
        forwards, backwards = POSITIVE[i] + OFFSET[i], NEGATIVE[i] - OFFSET[i]
        assert abs(values["coulomb_positive"] + values["offset"] - forwards) < 0.02 * abs(forwards)
        assert abs(values["coulomb_negative"] - values["offset"] - backwards) < 0.02 * abs(backwards)
        assert values["coulomb_positive"] >= 0 and values["coulomb_negative"] >= 0
        assert abs(values["armature"] - ARMATURE[i]) < 0.02 * ARMATURE[i]
        # not identified alone: no standard error of its own
        assert summary["joint_terms"]["std_errors"][joint]["offset"] is None
    assert consistent_error(summary) < 0.02


def test_smooth_coulomb_friction_is_recovered(tmp_path, arm):
    urdf, robot = arm
    data = drive_log(tmp_path / "log.csv", robot, offset=False, armature=False,
                     asymmetric=False, smooth=True)
    summary = identify(tmp_path, urdf, data, "on", "--smooth-coulomb", str(SMOOTH))
    sign = identify(tmp_path, urdf, data, "off")
    for i, joint in enumerate(robot.joint_names):
        assert abs(summary["coulomb"][joint] - FRICTION[i, 1]) < 0.02 * FRICTION[i, 1]
    assert summary["joint_terms"]["smooth_coulomb_velocity"] == SMOOTH
    rows = sidecar_rows(tmp_path / "on" / "joint_terms.csv")
    assert {term for _, term in rows} == {"smooth_coulomb_velocity"}
    on, off = consistent_error(summary), consistent_error(sign)
    assert off > 3 * on, (on, off)


def test_validate_reads_the_terms_beside_the_urdf(tmp_path, arm, capsys):
    urdf, robot = arm
    data = drive_log(tmp_path / "log.csv", robot, offset=False)
    identify(tmp_path, urdf, data, "id", "--joint-terms", "armature,asymmetric-coulomb")
    identified = tmp_path / "id" / "identified.urdf"
    capsys.readouterr()
    assert main(["validate", str(data), "--robot", str(identified),
                 "--out", str(tmp_path / "with")]) == 0
    assert "includes the joint terms" in capsys.readouterr().out
    report = json.loads((tmp_path / "with" / "validation.json").read_text())
    assert report["joint_terms"].endswith("joint_terms.csv")
    alone = tmp_path / "alone"
    alone.mkdir()
    (alone / "arm.urdf").write_bytes(identified.read_bytes())
    assert main(["validate", str(data), "--robot", str(alone / "arm.urdf"),
                 "--out", str(tmp_path / "without")]) == 0
    assert "joint terms" not in capsys.readouterr().out
    without = json.loads((tmp_path / "without" / "validation.json").read_text())
    assert without["joint_terms"] is None
    with_terms = report["relative_error"]["pooled"]
    # measured 0.00029 (the encoders' noise through the derivatives) and 0.35
    assert with_terms < 0.002 and without["relative_error"]["pooled"] > 100 * with_terms
    # named explicitly, the same prediction
    assert main(["validate", str(data), "--robot", str(alone / "arm.urdf"), "--joint-terms-file",
                 str(tmp_path / "id" / "joint_terms.csv"), "--out", str(tmp_path / "named")]) == 0
    named = json.loads((tmp_path / "named" / "validation.json").read_text())
    assert named["relative_error"]["pooled"] == pytest.approx(with_terms, rel=1e-12)


def test_an_identification_without_terms_leaves_an_empty_sidecar(tmp_path, arm):
    """A later run without terms must not leave an earlier run's terms beside its URDF."""
    urdf, robot = arm
    data = drive_log(tmp_path / "log.csv", robot, offset=False, seconds=4.0)
    identify(tmp_path, urdf, data, "id", "--joint-terms", "armature")
    assert sidecar_rows(tmp_path / "id" / "joint_terms.csv")
    summary = identify(tmp_path, urdf, data, "id", "--joint-terms", "none")
    assert "joint_terms" not in summary and "joint_terms_choice" not in summary
    assert sidecar_rows(tmp_path / "id" / "joint_terms.csv") == {}
    assert not read_sidecar(tmp_path / "id" / "joint_terms.csv", robot.joint_names).terms.any


@pytest.mark.parametrize("drive, chosen", [
    # two Coulomb levels are one symmetric level and an offset: the same model, fewer terms
    ({"offset": False, "armature": True, "asymmetric": True}, "offset,armature"),
    ({"offset": True, "armature": False, "asymmetric": False}, "offset"),
    ({"offset": False, "armature": False, "asymmetric": False}, "none"),
])
def test_auto_chooses_the_terms_the_drives_have(tmp_path, arm, capsys, drive, chosen):
    """--joint-terms auto: of the eight classes, the one the log's drives have (the
    fewest terms as good as the best on held-out blocks), printed and recorded."""
    urdf, robot = arm
    data = drive_log(tmp_path / "log.csv", robot, seconds=8.0, noise=0.02, **drive)
    summary = identify(tmp_path, urdf, data, "auto", "--joint-terms", "auto")
    record = summary["joint_terms_choice"]
    assert record["chosen"] == chosen, record["scores"]
    # every class scored, or refused with the reason (a Coulomb level the log puts below
    # zero where the truth has an offset: the log contradicts the class)
    assert len(record["scores"]) == 8
    assert all((v is None) == (k in record["refused"]) for k, v in record["scores"].items())
    best = min(v for v in record["scores"].values() if v is not None)
    assert record["scores"][chosen] <= 1.01 * best + 1e-3, record["scores"]
    printed = capsys.readouterr().out
    assert "joint terms by cross-validation" in printed and f"{chosen:<36}" in printed
    if chosen != "none":  # the chosen terms are identified and written as asked by name
        assert "joint_terms" in summary
    # each term of the class kept, left out, costs what the scores say; the offset the
    # drives have costs more than 1 % and is named
    costs = record["absence_costs"]
    assert set(costs) == set(chosen.split(",")) - {"none"}, costs
    for item, cost in costs.items():
        without = ",".join(k for k in chosen.split(",") if k != item) or "none"
        assert cost == pytest.approx(record["scores"][without] / record["scores"][chosen] - 1)
        assert (f"without {item} the class kept scores" in printed) == (cost > 0.01)
    if "offset" in chosen:
        assert costs["offset"] > 0.01, costs


def test_the_terms_are_chosen_by_default_and_none_names_the_core_model(tmp_path, arm):
    """Without --joint-terms the log chooses (as with auto); none and --smooth-coulomb
    alone give the core's model without a choice."""
    urdf, robot = arm
    data = drive_log(tmp_path / "log.csv", robot, asymmetric=False, seconds=8.0, noise=0.02)
    default = identify(tmp_path, urdf, data, "default")
    assert default["joint_terms_choice"]["chosen"] == "offset,armature"
    assert set(default["joint_terms"]["values"]["joint1"]) == {"offset", "armature"}
    none = identify(tmp_path, urdf, data, "none", "--joint-terms", "none")
    assert "joint_terms_choice" not in none and "joint_terms" not in none
    smooth = identify(tmp_path, urdf, data, "smooth", "--smooth-coulomb", "0.1")
    assert "joint_terms_choice" not in smooth


def test_a_class_the_log_contradicts_is_not_a_candidate(tmp_path, arm):
    """Torques unrelated to the motion (two sines): a negative armature explains them
    exactly, which no drive has; those classes are refused with the reason and the
    choice falls on a class without it."""
    urdf, _ = arm
    data = swing_log(tmp_path / "log.csv", np.arange(6000) * 1e-3)
    record = identify(tmp_path, urdf, data, "out")["joint_terms_choice"]
    assert "armature" not in record["chosen"]
    for name in ("armature", "offset,armature", "offset,armature,asymmetric-coulomb"):
        assert "joint1.armature = -3.698" in record["refused"][name]
        assert "the log contradicts it" in record["refused"][name]


@pytest.mark.parametrize("options, message", [
    (["--joint-terms", "auto", "--smooth-coulomb", "0.1"], "cannot join that choice"),
    (["--joint-terms", "none,offset"], "'none' is not one of"),
    (["--joint-terms", "offset,stiction"], "'stiction' is not one of"),
    (["--joint-terms", ","], "names no term"),
    (["--smooth-coulomb", "0"], "--smooth-coulomb"),
    (["--smooth-coulomb", "nan"], "--smooth-coulomb"),
    (["--joint-terms", "asymmetric-coulomb", "--smooth-coulomb", "0.1"], "cannot be combined"),
])
def test_bad_term_options_exit_2_naming_them(tmp_path, arm, capsys, options, message):
    urdf, robot = arm
    data = drive_log(tmp_path / "log.csv", robot, seconds=2.0)
    assert exit_code(["identify", str(data), "--robot", str(urdf), "--out",
                      str(tmp_path / "out"), *options]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out" / "summary.json").exists()


def test_term_options_need_robot(tmp_path, capsys):
    data = tmp_path / "log.csv"
    data.write_text("t,y,u\n0,0,0\n")
    assert exit_code(["identify", str(data), "--joint-terms", "offset", "--out",
                      str(tmp_path / "out")]) == 2
    assert "--joint-terms" in capsys.readouterr().err


def exit_code(arguments: list[str]) -> int:
    """The CLI's exit status: main's return value, or argparse's exit."""
    try:
        return main(arguments)
    except SystemExit as stop:
        return int(stop.code or 0)


@pytest.mark.parametrize("content, message", [
    ("joint,term,value,std_error,unit\njoint9,offset,1,,N.m\n", "joint 'joint9'"),
    ("joint,term,value,std_error,unit\njoint1,stiction,1,,N.m\n", "term 'stiction'"),
    ("joint,term,value,std_error,unit\njoint1,offset,x,,N.m\n", "not a finite number"),
    ("joint,term,value,std_error,unit\njoint1,offset,1,,N.m\n", "joint 'joint2' has no offset"),
    (b"joint,term,value,std_error,unit\njoint1,offset,\xff\n", "not a CSV file in UTF-8"),
    (b"joint,term,value\n" + b"x" * (1 << 20), "bytes; a joint_terms.csv is a few hundred"),
])
def test_bad_sidecars_exit_2_naming_the_row(tmp_path, arm, capsys, content, message):
    urdf, robot = arm
    data = drive_log(tmp_path / "log.csv", robot, seconds=2.0)
    terms = tmp_path / "terms.csv"
    if isinstance(content, bytes):
        terms.write_bytes(content)
    else:
        terms.write_text(content)
    assert main(["validate", str(data), "--robot", str(urdf), "--joint-terms-file", str(terms),
                 "--out", str(tmp_path / "out")]) == 2
    assert message in capsys.readouterr().err


def test_the_base_parameters_with_terms_reproduce_the_torques(arm):
    """Random states: Y_b beta = Y pi with the extra columns (offset 1 at joint i's row,
    armature q_i'', the Coulomb levels), the offset folded into the Coulomb levels."""
    _, robot = arm
    terms = JointTerms(offset=True, armature=True, asymmetric_coulomb=True)
    body = robot.rigid_body()
    base = base_parameters(body, robot.arrays()["types"], robot.joint_names, terms=terms)
    rng = np.random.default_rng(1)
    q, qd, qdd = random_states(robot.arrays()["types"], 50, rng)
    Y = terms.extend(body.regressor(q, qd, qdd), qd, qdd)
    layout = ParameterLayout(robot.n, len(terms.kinds))
    assert Y.shape == (50, robot.n, layout.size)
    assert np.all(Y[:, :, layout.coulomb_levels] == 0)  # the core's Coulomb column replaced
    pi = np.concatenate([robot.parameters(), rng.uniform(0.1, 1, terms.count(robot.n))])
    pi[layout.coulomb_levels] = 0.0  # replaced: not a parameter of this model
    assert np.allclose(base.regressor(Y) @ base.project(pi), Y @ pi, atol=1e-9)
    offsets = [f"{j}.offset" for j in robot.joint_names]
    assert set(offsets) <= set(base.dependent_names)
    assert not {f"{j}.fc" for j in robot.joint_names} & set(base.names + base.dependent_names)


def test_terms_parse_and_refuse():
    assert parse_terms("offset, armature", None) == JointTerms(offset=True, armature=True)
    assert parse_terms(None, 0.1) == JointTerms(smooth_coulomb=0.1)
    assert JointTerms(asymmetric_coulomb=True).kinds == ("coulomb_positive", "coulomb_negative")
    with pytest.raises(JointTermsError, match="> 0"):
        JointTerms(smooth_coulomb=-1.0)


def test_the_observer_method_takes_the_terms_in_momentum_form(tmp_path, arm):
    """--velocity observer: the terms through the regression's causal filter, the
    armature as the derivative of its momentum (30-bit encoders, as the observer test)."""
    urdf, robot = arm
    data = drive_log(tmp_path / "log.csv", robot, offset=False, seconds=6.0, bits=30)
    summary = identify(tmp_path, urdf, data, "on", "--velocity", "observer",
                       "--joint-terms", "armature,asymmetric-coulomb")
    for i, joint in enumerate(robot.joint_names):
        values = summary["joint_terms"]["values"][joint]
        for kind, truth in (("armature", ARMATURE), ("coulomb_positive", POSITIVE),
                            ("coulomb_negative", NEGATIVE)):
            assert abs(values[kind] - truth[i]) < 0.03 * truth[i], (joint, kind, values)


def test_a_joint_moving_one_way_only_is_named(tmp_path, arm, capsys):
    urdf, robot = arm
    truth = robot.rigid_body(link=payload_link(robot.arrays()["link"]), friction=FRICTION)
    t, q, qd, qdd, _ = multisine_log(truth, 4.0, 1e-3)
    q[:, 0] += 6.0 * t  # joint 1 turns forwards throughout
    qd[:, 0] += 6.0
    tau = truth.inverse_dynamics(q, qd, qdd)
    data = tmp_path / "log.csv"
    np.savetxt(data, np.column_stack([t, q, tau]), delimiter=",", header="t,q1,q2,u1,u2",
               comments="", fmt="%.17g")
    assert exit_code(["identify", str(data), "--robot", str(urdf), "--out",
                      str(tmp_path / "out"), "--joint-terms", "offset"]) == 2
    message = capsys.readouterr().err
    assert "'joint1' never moves backwards" in message and "joint2" not in message
    # without the offset, the symmetric model still identifies this log, without a
    # warning (both models' training errors are rounding: no ratio of them is one)
    summary = identify(tmp_path, urdf, data, "out", "--joint-terms", "armature")
    assert not summary["warnings"], summary["warnings"]
