"""--joints: the chain of one arm out of a branching URDF (a mobile base's wheels, a
finger), every other joint held at 0."""
from __future__ import annotations

import numpy as np
import pytest
from lxml import etree
from robot_helpers import branching_urdf

from harness.cli import main
from harness.robot.examples import example_urdf
from harness.robot.urdf import UrdfError, matrix_rpy, read_urdf, rpy_matrix


@pytest.fixture(scope="module")
def urdfs(tmp_path_factory):
    """The double pendulum, and the same on a base with two wheels and with a finger on
    its last link (a prismatic joint)."""
    folder = tmp_path_factory.mktemp("chain")
    arm, _ = example_urdf("double_pendulum")
    return arm, branching_urdf(folder), folder


def test_a_branching_urdf_names_the_option(urdfs):
    _, branching, _ = urdfs
    with pytest.raises(UrdfError, match="not a serial chain.*--joints"):
        read_urdf(branching)


def test_the_named_chain_is_the_arm_with_the_rest_held(urdfs):
    """The wheels hang from the fixed base: they weigh nothing on the arm. The finger, held
    at 0, is part of link 2's body: its mass and inertia join it."""
    arm, branching, _ = urdfs
    plain = read_urdf(arm)
    chain = read_urdf(branching, joints_used=("joint1", "joint2"))
    assert chain.joint_names == ["joint1", "joint2"]
    assert set(chain.locked) == {"wheel_left_joint", "wheel_right_joint", "finger_joint"}
    links, plain_links = chain.arrays()["link"], plain.arrays()["link"]
    assert np.array_equal(links[0], plain_links[0])
    assert links[1][0] == pytest.approx(plain_links[1][0] + 1.7)  # the finger's mass
    # the same as locking the three joints by hand
    by_hand = read_urdf(branching, locked=("wheel_left_joint", "wheel_right_joint",
                                           "finger_joint"))
    assert np.array_equal(by_hand.arrays()["link"], links)


@pytest.mark.parametrize("used, words", [
    (("joint2", "joint1"), "meets them in the order joint1,joint2"),
    (("joint1", "elbow"), "'elbow' is not a moving joint"),
    (("joint1", "joint1"), "'joint1' is named twice"),
    (("joint1", "wheel_left_joint"), "not a serial chain"),
])
def test_a_bad_chain_is_refused_by_name(urdfs, used, words):
    _, branching, _ = urdfs
    with pytest.raises(UrdfError, match=words):
        read_urdf(branching, joints_used=used)


def test_a_joint_both_named_and_locked_is_refused(urdfs):
    _, branching, _ = urdfs
    with pytest.raises(UrdfError, match="'joint2' is also locked"):
        read_urdf(branching, locked=("joint2",), joints_used=("joint1", "joint2"))


def test_every_robot_command_takes_it(urdfs, capsys):
    """robot-fmu-parameters of the branching URDF with --joints writes what locking by hand
    writes; identify refuses an empty name in the list by argparse (exit 2)."""
    _, branching, folder = urdfs
    assert main(["robot-fmu-parameters", str(branching), "--joints", "joint1,joint2",
                 "--out", str(folder / "named.ssv")]) == 0
    assert main(["robot-fmu-parameters", str(branching), "--lock", "wheel_left_joint",
                 "--lock", "wheel_right_joint", "--lock", "finger_joint",
                 "--out", str(folder / "locked.ssv")]) == 0
    assert (folder / "named.ssv").read_bytes() == (folder / "locked.ssv").read_bytes()
    with pytest.raises(SystemExit) as stop:
        main(["identify", "log.csv", "--robot", str(branching), "--joints", "joint1,,joint2",
              "--out", str(folder / "x")])
    assert stop.value.code == 2 and "a joint name is empty" in capsys.readouterr().err


def _fixed_at(path, folder, joint_name: str, rpy=None, xyz=None):
    """The URDF with one joint made fixed, its origin replaced."""
    tree = etree.parse(str(path))
    joint = tree.getroot().find(f"joint[@name='{joint_name}']")
    joint.set("type", "fixed")
    origin = joint.find("origin")
    if rpy is not None:
        origin.set("rpy", " ".join(repr(float(x)) for x in rpy))
    if xyz is not None:
        origin.set("xyz", " ".join(repr(float(x)) for x in xyz))
    out = folder / f"{joint_name}_fixed.urdf"
    tree.write(str(out))
    return out


def test_a_joint_locked_at_a_position_is_that_joint_made_fixed(urdfs):
    """--lock JOINT=POSITION: joint 2 of the arm held at 0.5 rad is the URDF whose joint 2
    is fixed with its origin turned by 0.5 rad about its axis (x); the prismatic finger
    held at 0.05 m, the finger's origin moved 0.05 m along its axis (y)."""
    arm, branching, folder = urdfs
    turned = rpy_matrix([0.0, 0.0, 0.0]) @ np.array(
        [[1.0, 0.0, 0.0], [0.0, np.cos(0.5), -np.sin(0.5)], [0.0, np.sin(0.5), np.cos(0.5)]])
    held = read_urdf(arm, locked={"joint2": 0.5})
    fixed = read_urdf(_fixed_at(arm, folder, "joint2", rpy=matrix_rpy(turned)))
    assert held.joint_names == ["joint1"] and held.locked_at == {"joint2": 0.5}
    np.testing.assert_allclose(held.arrays()["link"], fixed.arrays()["link"], rtol=1e-12,
                               atol=1e-15)
    assert not np.allclose(held.arrays()["link"], read_urdf(arm, locked=("joint2",))
                           .arrays()["link"])  # the position matters
    out = read_urdf(branching, locked={"finger_joint": 0.05},
                    joints_used=("joint1", "joint2"))
    moved = read_urdf(_fixed_at(branching, folder, "finger_joint", xyz=[0.1, 0.05, 0.0]),
                      joints_used=("joint1", "joint2"))
    np.testing.assert_allclose(out.arrays()["link"], moved.arrays()["link"], rtol=1e-12,
                               atol=1e-15)


@pytest.mark.parametrize("options, words", [
    (["--lock", "joint2=abc"], "--lock joint2 = 'abc' is not a number"),
    (["--lock", "joint2=nan"], "is not finite"),
    (["--lock", "=0.5"], "the joint name is empty"),
])
def test_a_bad_lock_position_is_refused_by_argparse(urdfs, capsys, options, words):
    arm, _, folder = urdfs
    with pytest.raises(SystemExit) as stop:
        main(["robot-fmu-parameters", str(arm), *options, "--out", str(folder / "x.ssv")])
    assert stop.value.code == 2 and words in capsys.readouterr().err


def test_a_lock_the_urdf_cannot_hold_is_refused_by_name(urdfs, capsys, tmp_path):
    """A joint locked twice, a fixed joint given a position, a position outside the
    joint's limits: exit 2 naming it, nothing written."""
    arm, _, _ = urdfs
    tree = etree.parse(str(arm))
    limit = tree.getroot().find("joint[@name='joint2']/limit")
    limit.set("lower", "-1")
    limit.set("upper", "1")
    limited = tmp_path / "limited.urdf"
    tree.write(str(limited))
    tree.getroot().find("joint[@name='joint2']").set("type", "fixed")
    fixed = tmp_path / "fixed.urdf"
    tree.write(str(fixed))
    for urdf, options, words in (
            (arm, ["--lock", "joint2", "--lock", "joint2=0.1"], "--lock names 'joint2' more "
                                                                "than once"),
            (fixed, ["--lock", "joint2=0.2"], "is fixed: it has no position to lock it at"),
            (limited, ["--lock", "joint2=1.5"], "locked at 1.5 rad, outside its limits "
                                                "[-1, 1] rad")):
        out = tmp_path / "x.ssv"
        assert main(["robot-fmu-parameters", str(urdf), *options, "--out", str(out)]) == 2
        assert words in capsys.readouterr().err
        assert not out.exists()
    assert main(["robot-fmu-parameters", str(limited), "--lock", "joint2=0.9", "--out",
                 str(tmp_path / "inside.ssv")]) == 0
