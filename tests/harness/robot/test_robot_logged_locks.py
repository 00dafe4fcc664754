"""Held joints at their logged position: a joint held out of the chain (left out by
--joints, or --lock without a position) whose column the log holds stands at the median
of that column; --lock JOINT=POSITION wins over the log, a joint without a column stays
at 0, and a logged joint that moves or stands outside its limits is refused by name."""
from __future__ import annotations

import json

import numpy as np
import pytest
from cli_runner import cli, refused
from lxml import etree
from robot_helpers import branching_urdf, swing_log

T = np.arange(3000) * 2e-3  # 6 s at 500 Hz
CHAIN = ["--joints", "joint1,joint2"]
FINGER = 0.05  # [m] where the finger stood while the arm swung


def _finger(position: float = FINGER, flicker: float = 2e-4) -> np.ndarray:
    """A still finger's column: its encoder flickering by one step either side."""
    return position + flicker * np.round(np.sin(37.0 * T))


@pytest.fixture(scope="module")
def mobile(tmp_path_factory):
    """The double pendulum on wheels with a finger (robot_helpers.branching_urdf)."""
    return branching_urdf(tmp_path_factory.mktemp("mobile"))


def _validate(tmp_path, urdf, data, *options: str) -> tuple[int, str, dict | None]:
    out = tmp_path / f"v{len(list(tmp_path.iterdir()))}"
    code, text = cli(["validate", str(data), "--robot", str(urdf), "--out", str(out),
                      *options])
    result = out / "validation.json"
    return code, text, json.loads(result.read_text()) if result.exists() else None


def test_a_logged_position_is_the_position_given(mobile, tmp_path):
    """A log with a finger_joint column: validate scores the chain with the finger at its
    median, exactly as --lock finger_joint=MEDIAN on the log without the column does, and
    says so (and validation.json where each position comes from); a bare --lock finger_joint takes the log too, --lock finger_joint=0 does not."""
    logged = swing_log(tmp_path / "logged.csv", T, {"finger_joint": _finger()})
    plain = swing_log(tmp_path / "plain.csv", T)
    median = float(np.median(_finger()))
    code, text, from_log = _validate(tmp_path, mobile, logged, *CHAIN)
    assert code == 0, text
    assert "finger_joint: held at 0.05 m, its logged position (median of column " \
           "'finger_joint'" in text
    code, text, given = _validate(tmp_path, mobile, plain, *CHAIN,
                                  "--lock", f"finger_joint={median!r}")
    assert code == 0, text
    assert from_log is not None and from_log["relative_error"] == given["relative_error"]
    finger = from_log["held_joints"]["finger_joint"]
    assert finger["source"] == "log" and finger["column"] == "finger_joint"
    assert finger["position"] == pytest.approx(median)
    assert given["held_joints"]["finger_joint"] == {"position": median, "source": "given"}
    code, text, bare = _validate(tmp_path, mobile, logged, "--joints", "joint1,joint2",
                                 "--lock", "finger_joint")
    assert code == 0 and bare["relative_error"] == from_log["relative_error"], text
    code, text, zero = _validate(tmp_path, mobile, logged, *CHAIN, "--lock", "finger_joint=0")
    _, _, unlogged = _validate(tmp_path, mobile, plain, *CHAIN)
    assert code == 0 and "held at" not in text, text
    assert zero["relative_error"] == unlogged["relative_error"] != from_log["relative_error"]


def test_summary_json_says_where_each_position_comes_from(mobile, tmp_path):
    """identify: the finger from its column, the left wheel from --lock although the log
    has its column too (the option wins), the right wheel without a column at 0."""
    data = swing_log(tmp_path / "log.csv", T, {"finger_joint": _finger(),
                                               "wheel_left_joint": np.full(T.shape, 1.0)})
    out = tmp_path / "out"
    code, text = cli(["identify", str(data), "--robot", str(mobile), "--out", str(out),
                      "--unknown", "payload", *CHAIN, "--lock", "wheel_left_joint=0.3"])
    assert code in (0, 1), text  # 1: identify's warnings on a short swing
    summary = json.loads((out / "summary.json").read_text())
    locked = summary["held_joints"]
    assert summary["locked_joints"] == {name: entry["position"] for name, entry in locked.items()}
    finger = locked.pop("finger_joint")
    assert finger["source"] == "log" and finger["column"] == "finger_joint"
    assert finger["position"] == pytest.approx(FINGER, abs=2e-4)
    assert finger["low"] == pytest.approx(FINGER - 2e-4)
    assert finger["high"] == pytest.approx(FINGER + 2e-4)
    assert locked == {"wheel_left_joint": {"position": 0.3, "source": "given"},
                      "wheel_right_joint": {"position": 0.0, "source": "default"}}


def test_a_held_joint_that_moves_is_refused_naming_it(mobile, tmp_path):
    """A finger that opens by 2 cm during the log: exit 2 naming the joint, its range and
    the ways out, nothing written; --lock finger_joint=POSITION is the user's choice."""
    data = swing_log(tmp_path / "moving.csv", T, {"finger_joint": 0.04 + 0.01 * np.sin(T)})
    for command in ("identify", "validate"):
        out = tmp_path / command
        code, text = cli([command, str(data), "--robot", str(mobile), "--out", str(out),
                          *CHAIN])
        assert code == 2
        refused(code, text, "joint 'finger_joint' is held out of the chain",
                "(column 'finger_joint') spans 0.02 m (from 0.03 to 0.05 m), more than "
                "0.001 m", "--joints", "--lock finger_joint=POSITION")
        assert not out.exists()
    code, text, _ = _validate(tmp_path, mobile, data, *CHAIN, "--lock", "finger_joint=0.045")
    assert code == 0 and "held at" not in text, text


def test_a_logged_position_outside_the_limits_is_refused(mobile, tmp_path):
    tree = etree.parse(str(mobile))
    joint = tree.getroot().find("joint[@name='finger_joint']")
    etree.SubElement(joint, "limit", lower="0", upper="0.04", effort="1", velocity="1")
    limited = tmp_path / "limited.urdf"
    tree.write(str(limited))
    data = swing_log(tmp_path / "log.csv", T, {"finger_joint": _finger()})
    code, text, _ = _validate(tmp_path, limited, data, *CHAIN)
    assert code == 2
    refused(code, text, "joint 'finger_joint': locked at 0.05 m (its logged position, the "
                        "median of column 'finger_joint'), outside its limits [0, 0.04] m")


def test_columns_maps_a_held_joint_and_its_unit_applies(mobile, tmp_path):
    """--columns finger_joint=grip reads another column; a column in mm takes
    --length-unit mm (the chain itself has no prismatic joint); --columns for a joint
    --lock places, or for no joint at all, is refused naming it."""
    data = swing_log(tmp_path / "grip.csv", T, {"grip": 1000.0 * _finger()})
    code, text, _ = _validate(tmp_path, mobile, data, *CHAIN, "--columns", "finger_joint=grip",
                              "--length-unit", "mm")
    assert code == 0 and "finger_joint: held at 0.05 m" in text, text
    code, text, _ = _validate(tmp_path, mobile, data, *CHAIN, "--columns", "finger_joint=grip",
                              "--lock", "finger_joint=0.01")
    refused(code, text, "--columns finger_joint=grip: joint 'finger_joint' is held at 0.01 by "
                        "--lock finger_joint=POSITION; leave out one of the two")
    code, text, _ = _validate(tmp_path, mobile, data, *CHAIN, "--columns", "thumb=grip")
    refused(code, text, "--columns names 'thumb'", "held joints: wheel_left_joint, "
                        "wheel_right_joint, finger_joint")


def test_a_log_without_the_column_holds_the_joint_at_0_as_before(mobile, tmp_path):
    """robot-fmu-parameters reads no log: every held joint at 0 unless --lock places it,
    a bare --lock included."""
    out = tmp_path / "bare.ssv"
    assert cli(["robot-fmu-parameters", str(mobile), *CHAIN, "--lock", "finger_joint",
                "--out", str(out)])[0] == 0
    assert cli(["robot-fmu-parameters", str(mobile), "--lock", "wheel_left_joint",
                "--lock", "wheel_right_joint", "--lock", "finger_joint=0",
                "--out", str(tmp_path / "zero.ssv")])[0] == 0
    assert out.read_bytes() == (tmp_path / "zero.ssv").read_bytes()
