"""The edges of what a URDF may say: a link without <inertial> is a massless link (legal
URDF) and every command works with it, identified.urdf included; numbers at the edges
of float64 (a subnormal mass, 5e-324) are refused by name with exit status 2."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from cli_runner import REPO, cli
from test_urdf_files import arm, both_commands

pytestmark = pytest.mark.cli

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
