"""Reading URDFs: the flat arrays of the C model, and a clear error for each bad input."""
from __future__ import annotations

import numpy as np
import pytest
from robot_helpers import random_chain_urdf

from harness.robot.examples import example_urdf
from harness.robot.urdf import UrdfError, matrix_rpy, read_urdf, rpy_matrix

LINK = ('<link name="{name}"><inertial><mass value="{mass}"/>'
        '<inertia ixx="{ixx}" ixy="0" ixz="0" iyy="{iyy}" iyz="0" izz="{izz}"/></inertial></link>')


def chain(tmp_path, joints: int = 2, mass: float = 1.0, moments=(0.1, 0.1, 0.1), extra: str = ""):
    """A URDF file of a planar chain of `joints` revolute joints."""
    ixx, iyy, izz = moments
    links = ['<link name="base"/>'] + [LINK.format(name=f"l{i}", mass=mass, ixx=ixx, iyy=iyy,
                                                   izz=izz) for i in range(joints)]
    parts = [f'<joint name="j{i}" type="revolute"><parent link="{"base" if i == 0 else f"l{i - 1}"}"/>'
             f'<child link="l{i}"/><origin xyz="0 0 0.5"/><axis xyz="0 1 0"/></joint>'
             for i in range(joints)]
    path = tmp_path / "robot.urdf"
    path.write_text('<robot name="r">' + "".join(links + parts) + extra + "</robot>")
    return path


def test_flat_arrays_of_a_chain(tmp_path):
    robot = read_urdf(chain(tmp_path, joints=3, mass=2.0))
    arrays = robot.arrays()
    assert robot.n == 3 and robot.joint_names == ["j0", "j1", "j2"]
    assert arrays["types"].tolist() == [0, 0, 0]
    assert np.allclose(arrays["axis"], [[0, 1, 0]] * 3)
    assert np.allclose(arrays["xyz"], [[0, 0, 0.5]] * 3)
    assert np.allclose(arrays["link"][0], [2.0, 0, 0, 0, 0.1, 0, 0.1, 0, 0, 0.1])
    assert robot.parameters().shape == (36,)


def test_rpy_round_trip():
    rng = np.random.default_rng(3)
    for rpy in [*rng.uniform(-3, 3, (20, 3)), [0.3, np.pi / 2, 0.1], [0.2, -np.pi / 2, 1.0]]:
        R = rpy_matrix(rpy)
        assert np.allclose(rpy_matrix(matrix_rpy(R)), R, atol=1e-14)


def test_fixed_links_are_merged_and_locked_joints_fixed(tmp_path):
    path = tmp_path / "chain.urdf"
    path.write_text(random_chain_urdf(np.random.default_rng(5), ["revolute"] * 3))
    robot = read_urdf(path)
    assert sorted(robot.joints[0].merged_links) == ["f0", "sensor0"]
    locked = read_urdf(path, locked=("j2",))
    assert locked.n == 2
    # the locked joint's link now belongs to the second body: it weighs more
    assert locked.joints[1].link[0] > robot.joints[1].link[0]


def test_panda_needs_its_fingers_locked():
    path, locked = example_urdf("panda")
    with pytest.raises(UrdfError, match="mimics another joint; lock it"):
        read_urdf(path, locked=("panda_finger_joint1",))
    assert read_urdf(path, locked=locked).n == 7


@pytest.mark.parametrize("text, message", [("<robot><link name='a'>", "does not parse as XML"),
                                           ("<sdf/>", "not a URDF"),
                                           (None, "cannot read")])
def test_unreadable_files(tmp_path, text, message):
    path = tmp_path / "robot.urdf"
    if text is not None:
        path.write_text(text)
    with pytest.raises(UrdfError, match=message):
        read_urdf(path)


def test_bad_robots(tmp_path):
    cases = [
        (dict(joints=13), "13 moving joints; at most 12"),
        (dict(mass=-1.0), "negative mass -1"),
        (dict(moments=(0.1, -0.1, 0.1)), "not positive definite"),
        (dict(moments=(0.1, 0.1, 0.3)), "triangle inequality"),
        (dict(extra='<link name="x"/><joint name="branch" type="revolute"><parent link="l0"/>'
                    '<child link="x"/><axis xyz="0 0 1"/></joint>'),
         "not a serial chain: link 'l0' branches into joints 'j1', 'branch'"),
        (dict(extra='<link name="x"/><joint name="free" type="floating"><parent link="l1"/>'
                    '<child link="x"/></joint>'), "joint 'free' is of type 'floating'"),
        (dict(extra='<link name="x"/><joint name="bad" type="fixed"><parent link="l1"/>'
                    '<child link="nowhere"/></joint>'), "does not name an existing"),
        (dict(extra='<link name="x"/>'), "expected one root link, found 2"),
    ]
    for kwargs, message in cases:
        with pytest.raises(UrdfError, match=message):
            read_urdf(chain(tmp_path, **kwargs))


def test_unknown_locked_joint(tmp_path):
    with pytest.raises(UrdfError, match="locked joint.*'j9' not in the URDF"):
        read_urdf(chain(tmp_path), locked=("j9",))


def test_locking_seven_of_eight_joints_is_accepted(tmp_path):
    assert read_urdf(chain(tmp_path, joints=8), locked=("j7",)).n == 7


def test_bad_numbers_name_the_place(tmp_path):
    path = chain(tmp_path)
    path.write_text(path.read_text().replace('xyz="0 0 0.5"', 'xyz="0 zero 0.5"', 1))
    with pytest.raises(UrdfError, match="joint 'j0': xyz='0 zero 0.5' is not 3 numbers"):
        read_urdf(path)
    path.write_text(path.read_text().replace('xyz="0 zero 0.5"', 'xyz="0 1_0 0.5"', 1))
    with pytest.raises(UrdfError, match="joint 'j0': xyz='0 1_0 0.5' is not 3 numbers"):
        read_urdf(path)  # Python's float() reads 1_0 as 10, an XML double has no "_"


@pytest.mark.parametrize("value, said", [("nan", "is not 1 finite numbers"),
                                         ("-1", "negative mass")])
def test_a_bad_mass_is_refused_on_every_link_also_the_fixed_root(tmp_path, value, said):
    """The root's inertial is not used (it does not move), but a value that cannot be a
    mass is an error in the file wherever it stands."""
    text = open(example_urdf("double_pendulum")[0]).read()
    path = tmp_path / "robot.urdf"
    path.write_text(text.replace('value="0.10159"', f'value="{value}"', 1))
    with pytest.raises(UrdfError, match=f"link 'base_link' <inertial>: .*{said}"):
        read_urdf(path)
