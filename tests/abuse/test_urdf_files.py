"""URDFs built to break the reader: long chains, entities, closed loops, absurd
numbers.  Each command refuses them with exit status 2 and a message naming the
file and the place, before it writes anything; none raises a traceback."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from cli_runner import cli, refused

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
