"""URDFs built to break the reader: long chains, entities, closed loops, absurd
numbers.  Each command refuses them with exit status 2 and a message naming the
file and the place, before it writes anything; none raises a traceback.

The edges of what a URDF may say: a link without <inertial> is a massless link (legal
URDF) and every command works with it, identified.urdf included; numbers at the edges
of float64 (a subnormal mass, 5e-324) are refused by name with exit status 2.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from cli_runner import REPO, cli, refused

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


LINK = ('<link name="{name}"><inertial><origin xyz="{com}"/><mass value="{mass}"/>'
        '<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>')
JOINT = ('<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
         '<origin xyz="{xyz}"/><axis xyz="{axis}"/></joint>')


def arm(path: Path, head: str = "", extra: str = "", mass: str = "1", xyz: str = "0 0 0.5",
        axis: str = "0 1 0", fixed: int = 0) -> Path:
    """A two-joint arm; ``fixed`` fixed links between the base and the first joint."""
    links = ['<link name="base"/>', LINK.format(name="l0", com="0 0 0.1", mass=mass),
             LINK.format(name="l1", com="0 0 0.1", mass="1")]
    joints = [JOINT.format(name="j0", kind="revolute", parent=f"f{fixed}" if fixed else "base",
                           child="l0", xyz=xyz, axis=axis),
              JOINT.format(name="j1", kind="revolute", parent="l0", child="l1", xyz="0 0 0.5",
                           axis="0 1 0")]
    for k in range(1, fixed + 1):
        links.append(f'<link name="f{k}"/>')
        joints.append(JOINT.format(name=f"fixed{k}", kind="fixed",
                                   parent="base" if k == 1 else f"f{k - 1}", child=f"f{k}",
                                   xyz="0 0 0.001", axis="1 0 0"))
    path.write_text(head + '<robot name="arm">' + "".join(links + joints) + extra + "</robot>")
    return path


def log(path: Path) -> Path:
    t = 1e-3 * np.arange(3000)
    q = np.column_stack([np.sin(t), np.cos(2 * t)])
    np.savetxt(path, np.column_stack([t, q, q]), delimiter=",", header="t,q1,q2,u1,u2",
               comments="", fmt="%.17g")
    return path


def both_commands(tmp_path: Path, urdf: Path, *words: str) -> None:
    """robot-fmu-parameters and identify --robot refuse it and write nothing."""
    ssv = tmp_path / "robot.ssv"
    code, text = cli(["robot-fmu-parameters", str(urdf), "--out", str(ssv)])
    assert code == 2, text
    refused(code, text, str(urdf), *words)
    out = tmp_path / "out"
    code, text = cli(["identify", str(log(tmp_path / "log.csv")), "--robot", str(urdf),
                      "--out", str(out)])
    assert code == 2, text
    refused(code, text, str(urdf), *words)
    assert not ssv.exists() and not out.exists()


def test_a_chain_of_thousands_of_fixed_links_is_read(tmp_path):
    urdf = arm(tmp_path / "long.urdf", fixed=3000)
    code, text = cli(["robot-fmu-parameters", str(urdf), "--out", str(tmp_path / "r.ssv")])
    assert code == 0, text
    assert "2 joints" in text


@pytest.mark.parametrize("head, use", [
    ('<!DOCTYPE robot [<!ENTITY name SYSTEM "file:///etc/hostname">]>', "&name;"),
    ('<!DOCTYPE robot [<!ENTITY % p SYSTEM "file:///nonexistent/p.dtd"> %p;]>', ""),
    ('<!DOCTYPE robot [<!ENTITY big "xxxxxxxxxxxxxxxx">]>', "&big;"),
    ('<!DOCTYPE robot SYSTEM "http://example.invalid/robot.dtd">', ""),
])
def test_entities_are_refused_before_anything_is_written(tmp_path, head, use):
    urdf = arm(tmp_path / "entity.urdf", head=head,
               extra=f'<link name="tip{use}"/>' if use else "")
    both_commands(tmp_path, urdf, "entities")


def test_a_closed_loop_beside_the_tree_is_refused(tmp_path):
    loop = ('<link name="a"/><link name="b"/>'
            + JOINT.format(name="ab", kind="revolute", parent="a", child="b", xyz="0 0 0",
                           axis="0 0 1")
            + JOINT.format(name="ba", kind="revolute", parent="b", child="a", xyz="0 0 0",
                           axis="0 0 1"))
    both_commands(tmp_path, arm(tmp_path / "loop.urdf", extra=loop), "closed loop", "'a'")


@pytest.mark.parametrize("change, words", [
    ({"axis": "1e200 1e200 0"}, ["joint 'j0'", "axis"]),
    ({"xyz": "0 0 1e300"}, ["joint 'j0'", "xyz"]),
    ({"mass": "1e300"}, ["link 'l0'", "mass"]),
    ({"axis": "1e-300 0 0"}, ["joint 'j0'", "axis is zero"]),
])
def test_absurd_numbers_are_clean_errors(tmp_path, change, words):
    both_commands(tmp_path, arm(tmp_path / "absurd.urdf", **change), *words)


ARM = REPO / "examples" / "robot_arm" / "arm.urdf"  # three revolute joints


def without_inertial(path: Path, link: str) -> Path:
    """The example arm with ``link``'s <inertial> taken out."""
    text = ARM.read_text()
    pattern = re.compile(rf'(<link name="{link}">\s*)<inertial>.*?</inertial>', re.DOTALL)
    changed, count = pattern.subn(r"\1", text)
    assert count == 1
    path.write_text(changed)
    return path


def swing(path: Path) -> Path:
    """Three joints swinging, torques unrelated to the arm: the fit is poor and
    identified.urdf falls back to the URDF's own inertials (massless links included)."""
    t = 1e-3 * np.arange(6000)
    q = np.column_stack([0.8 * np.sin(1.3 * t), 0.6 * np.sin(2.1 * t), 0.5 * np.sin(3.1 * t)])
    u = np.column_stack([5.0 * np.sin(1.3 * t), 2.0 * np.cos(2.1 * t), np.cos(0.7 * t)])
    np.savetxt(path, np.column_stack([t, q, u]), delimiter=",",
               header="t,q1,q2,q3,u1,u2,u3", comments="", fmt="%.17g")
    return path


@pytest.mark.parametrize("link", ["turret", "forearm"])
def test_identify_with_a_massless_link_writes_a_readable_urdf(tmp_path, link):
    urdf = without_inertial(tmp_path / "arm.urdf", link)
    out = tmp_path / "out"
    code, text = cli(["identify", str(swing(tmp_path / "log.csv")), "--robot", str(urdf),
                      "--out", str(out)])
    assert code in (0, 1), text  # written; a fit this poor may be warned about
    identified = out / "identified.urdf"
    assert identified.exists(), text
    code, text = cli(["validate", str(tmp_path / "log.csv"), "--robot", str(identified),
                      "--out", str(tmp_path / "val")])
    assert code in (0, 1), text


def test_the_urdf_writer_keeps_a_massless_link_massless(tmp_path):
    from harness.robot.consistency import write_identified_urdf
    from harness.robot.urdf import read_urdf

    robot = read_urdf(without_inertial(tmp_path / "arm.urdf", "forearm"))
    written = tmp_path / "identified.urdf"
    write_identified_urdf(robot, robot.parameters(), written, "the URDF's own values")
    again = read_urdf(written)
    assert again.joints[-1].link[0] == 0.0  # still massless
    assert np.allclose(again.parameters(), robot.parameters())


@pytest.mark.parametrize("mass, words", [
    ("5e-324", ["link 'l0'", "5e-324", "subnormal"]),
    ("1e-310", ["link 'l0'", "1e-310", "subnormal"]),
    ("1e-30", ["link 'l0'", "mass 1e-30", "massless"]),
])
def test_a_mass_at_the_edge_of_float64_is_refused_by_name(tmp_path, mass, words):
    both_commands(tmp_path, arm(tmp_path / "tiny.urdf", mass=mass), *words)


def test_a_subnormal_inertia_is_refused_by_name(tmp_path):
    urdf = arm(tmp_path / "arm.urdf")
    urdf.write_text(urdf.read_text().replace('ixy="0"', 'ixy="4e-320"', 1))
    both_commands(tmp_path, urdf, "link 'l0'", "ixy", "subnormal")


def test_a_zero_mass_is_a_massless_link(tmp_path):
    code, text = cli(["robot-fmu-parameters", str(arm(tmp_path / "arm.urdf", mass="0")),
                      "--out", str(tmp_path / "r.ssv")])
    assert code == 0, text
    assert "2 joints" in text
