"""Numbers at the edges of float64 in a robot's options and joint_terms.csv: a drive
gain of 1e300, an armature of 1e308, a term given twice, are refused with exit status 2
and a message naming the option or the line, never a traceback or a silent choice."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from cli_runner import cli, refused

pytestmark = pytest.mark.cli


@pytest.fixture(scope="module")
def urdf() -> Path:
    from harness.robot.examples import example_urdf
    return Path(example_urdf("double_pendulum")[0])


def names(urdf: Path) -> list[str]:
    from harness.robot.urdf import read_urdf
    return read_urdf(urdf).joint_names


def swing(path: Path) -> Path:
    t = 1e-3 * np.arange(4000)
    q = np.column_stack([0.8 * np.sin(1.3 * t), 0.6 * np.sin(2.1 * t)])
    u = np.column_stack([5.0 * np.sin(1.3 * t), 2.0 * np.cos(2.1 * t)])
    np.savetxt(path, np.column_stack([t, q, u]), delimiter=",", header="t,q1,q2,u1,u2",
               comments="", fmt="%.17g")
    return path


@pytest.mark.parametrize("command", ["identify", "validate"])
@pytest.mark.parametrize("gains, word", [("1e300,1", "1e300"), ("1,1e-300", "1e-300")])
def test_drive_gains_beyond_the_range_are_refused(tmp_path, urdf, command, gains, word):
    code, text = cli([command, str(swing(tmp_path / "log.csv")), "--robot", str(urdf),
                      "--torque-gains", gains, "--out", str(tmp_path / "out")])
    assert code == 2, text
    refused(code, text, "--torque-gains", word)


def sidecar(path: Path, joints: list[str], rows: list[tuple[str, str, str]]) -> Path:
    lines = ["joint,term,value,std_error,unit"]
    lines += [f"{joints[j]},{term},{value},," for j, term, value in
              ((int(j), term, value) for j, term, value in rows)]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_an_armature_of_1e308_is_refused_naming_its_line(tmp_path, urdf):
    joints = names(urdf)
    terms = sidecar(tmp_path / "joint_terms.csv", joints,
                    [("0", "armature", "1e308"), ("1", "armature", "0.1")])
    code, text = cli(["validate", str(swing(tmp_path / "log.csv")), "--robot", str(urdf),
                      "--joint-terms-file", str(terms), "--out", str(tmp_path / "out")])
    assert code == 2, text
    refused(code, text, "joint_terms.csv line 2", "1e308")


def test_a_term_given_twice_is_refused_naming_both_lines(tmp_path, urdf):
    from harness.robot.joint_terms import JointTermsError, read_sidecar

    joints = names(urdf)
    terms = sidecar(tmp_path / "joint_terms.csv", joints,
                    [("0", "offset", "0.1"), ("1", "offset", "0.2"), ("0", "offset", "0.3")])
    with pytest.raises(JointTermsError, match=r"line 4: .* second offset \(line 2\)"):
        read_sidecar(terms, joints)
