"""A robot's joint_terms.csv at its edges (harness/robot/joint_terms.py): an armature of
1e308 or a term given twice is refused naming its line(s), a file on a device is read
with a cap, and a joint_terms.csv beside the URDF that is no file is refused, never a
traceback or a silent choice."""
from __future__ import annotations

import os
import resource
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from cli_runner import REPO, cli, refused
from robot_helpers import swing_log

from harness.robot.examples import example_urdf
from harness.robot.urdf import read_urdf

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


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


def test_a_joint_term_given_twice_is_refused_naming_the_joint(tmp_path):
    from harness.robot.joint_terms import JointTermsError, read_sidecar
    path = tmp_path / "joint_terms.csv"
    path.write_text("joint,term,value,std_error,unit\nj1,offset,0.1,0,rad\nj2,offset,0.2,0,rad\n"
                    "j1,offset,0.3,0,rad\n")
    with pytest.raises(JointTermsError, match="joint 'j1' has a second offset"):
        read_sidecar(path, ["j1", "j2"])


def _limited() -> None:
    """The child's address space: a reader that trusts st_size fails, not the machine."""
    resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))


def test_joint_terms_file_on_a_device_is_read_with_a_cap(tmp_path):
    link = tmp_path / "joint_terms.csv"
    link.symlink_to(os.devnull.replace("null", "zero"))
    code = ("import sys\nfrom harness.robot.joint_terms import JointTermsError, read_sidecar\n"
            "try:\n    read_sidecar(sys.argv[1], ['j0'])\n"
            "except JointTermsError as error:\n    print(error)\n")
    result = subprocess.run([sys.executable, "-c", code, str(link)], cwd=REPO,
                            capture_output=True, text=True, timeout=60, preexec_fn=_limited)
    assert result.returncode == 0 and "larger than" in result.stdout, result.stderr[-2000:]


@pytest.fixture(scope="module")
def arm():
    path, _ = example_urdf("double_pendulum")
    return path, read_urdf(path)


def test_a_joint_terms_name_beside_the_urdf_that_is_no_file_is_refused(tmp_path, arm):
    """A folder (or a pipe, a device) named joint_terms.csv beside the URDF: validate
    would otherwise predict with the URDF alone and say nothing."""
    import shutil

    from cli_runner import cli, refused
    urdf, _ = arm
    copy = tmp_path / "robot.urdf"
    shutil.copy(urdf, copy)
    (tmp_path / "joint_terms.csv").mkdir()
    data = swing_log(tmp_path / "log.csv", np.arange(6000) * 1e-3)
    code, text = cli(["validate", str(data), "--robot", str(copy), "--out", str(tmp_path / "o")])
    assert code == 2, text
    refused(code, text, "joint_terms.csv", "not a regular file")
