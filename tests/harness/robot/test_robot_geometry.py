"""--com-in-geometry: the box of a body's shapes (harness.robot.geometry) holds its centre
of mass in the consistent model."""
from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh
from lxml import etree
from robot_helpers import multisine_log, payload_link

from harness.cli import main
from harness.robot.examples import example_urdf
from harness.robot.geometry import com_boxes
from harness.robot.urdf import body_inertial, read_urdf

CHAIN = """<robot name="shapes">
  <link name="base"/>
  <link name="arm">
    <inertial><mass value="1"/><origin xyz="0 0 0.1"/>
      <inertia ixx="0.01" iyy="0.01" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0 0 0.1"/><geometry><box size="0.02 0.04 0.2"/></geometry></collision>
    <collision><origin xyz="0 0 0.2" rpy="1.5707963267948966 0 0"/>
      <geometry><cylinder radius="0.03" length="0.1"/></geometry></collision>
  </link>
  <link name="tool">
    <inertial><mass value="0.5"/>
      <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><mesh filename="{mesh}" scale="2 2 2"/></geometry></visual>
  </link>
  <link name="hand">
    <inertial><mass value="0.2"/>
      <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
  <link name="bare">
    <inertial><mass value="0.1"/>
      <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 0 1"/></joint>
  <joint name="fixed_tool" type="fixed"><parent link="arm"/><child link="tool"/>
    <origin xyz="0 0 0.3"/></joint>
  <joint name="j2" type="revolute"><parent link="tool"/><child link="hand"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 1 0"/></joint>
  <joint name="j3" type="revolute"><parent link="hand"/><child link="bare"/>
    <axis xyz="1 0 0"/></joint>
</robot>
"""


def chain(folder, mesh: str):
    """The chain above, its tool's mesh a 0.02 m cube about (0, 0, 0.01) (scaled by 2)."""
    package = folder / "my_robot"
    (package / "meshes").mkdir(parents=True)
    trimesh.creation.box(extents=(0.02, 0.02, 0.02)).apply_translation((0, 0, 0.01)).export(
        package / "meshes" / "tool.stl")
    path = package / "robot.urdf"
    path.write_text(CHAIN.format(mesh=mesh))
    return read_urdf(path)


@pytest.mark.parametrize("mesh", ["meshes/tool.stl", "package://my_robot/meshes/tool.stl"])
def test_the_box_holds_every_shape_of_the_body_in_its_joint_frame(tmp_path, mesh):
    robot = chain(tmp_path, mesh)
    boxes, missing = com_boxes(robot)
    # arm: the box (x +-0.01, y +-0.02, z 0..0.2), the cylinder turned to lie along y
    # (x, z +-0.03 about z = 0.2, y +-0.05), and the tool 0.3 up: the mesh scaled by 2
    # (x, y +-0.02, z 0..0.04)
    low, high = boxes[0]
    assert low == pytest.approx([-0.03, -0.05, 0.0])
    assert high == pytest.approx([0.03, 0.05, 0.34])
    low, high = boxes[1]  # hand: the sphere about its joint frame
    assert low == pytest.approx([-0.05] * 3) and high == pytest.approx([0.05] * 3)
    assert set(boxes) == {0, 1}
    assert missing == {"bare": "link 'bare' has mass but no <collision> or <visual> shape"}


def test_a_mesh_that_cannot_be_found_is_named(tmp_path):
    robot = chain(tmp_path, "package://other_robot/meshes/tool.stl")
    boxes, missing = com_boxes(robot)
    assert 0 not in boxes and 1 in boxes
    assert "package://other_robot/meshes/tool.stl is not found" in missing["arm"]


@pytest.fixture(scope="module")
def arm(tmp_path_factory):
    """The double pendulum with primitive shapes; link2's box is x in [0, 0.01] about its
    joint axis (x), where the URDF's centre of mass lies at x = -0.005: the log cannot
    tell the first moment along the axis, so only the box moves it."""
    folder = tmp_path_factory.mktemp("geometry")
    path, _ = example_urdf("double_pendulum")
    tree = etree.parse(str(path))
    for link in tree.getroot().iter("link"):
        for element in link.findall("collision") + link.findall("visual"):
            link.remove(element)
        size, xyz = {"link2": ("0.01 0.04 0.26", "0.005 0 0.1")}.get(
            link.get("name"), ("0.1 0.1 0.3", "0 0 0.05"))
        shape = etree.SubElement(link, "collision")
        etree.SubElement(shape, "origin", xyz=xyz)
        etree.SubElement(etree.SubElement(shape, "geometry"), "box", size=size)
    urdf = folder / "arm.urdf"
    tree.write(str(urdf))
    robot = read_urdf(urdf)
    truth = robot.rigid_body(link=payload_link(robot.arrays()["link"]))
    t, q, _, _, tau = multisine_log(truth, 10.0, 1e-3)
    data = folder / "log.csv"
    np.savetxt(data, np.column_stack([t, q, tau]), delimiter=",",
               header="t,q1,q2,u1,u2", comments="", fmt="%.17g")
    return urdf, data


def centre_of_mass_x(urdf) -> float:
    return float(body_inertial(read_urdf(urdf).joints[1].link)[1][0])


@pytest.mark.parametrize("bounded", [False, True])
def test_the_box_holds_the_consistent_centre_of_mass(arm, tmp_path, bounded):
    urdf, data = arm
    options = ["--com-in-geometry"] if bounded else []
    assert main(["identify", str(data), "--robot", str(urdf), "--joint-terms", "none",
                 "--out", str(tmp_path), *options]) in (0, 1)
    summary = json.loads((tmp_path / "summary.json").read_text())
    x = centre_of_mass_x(tmp_path / "identified.urdf")
    if bounded:
        assert -1e-7 <= x <= 0.01 + 1e-7, x
        boxes = summary["mass_bounds"]["com_boxes"]
        assert boxes["link2"]["low"] == pytest.approx([0.0, -0.02, -0.03])
        assert summary["mass_bounds"]["without_com_box"] == {}
    else:
        assert x == pytest.approx(-0.005, abs=1e-3)
        assert summary["mass_bounds"] is None
