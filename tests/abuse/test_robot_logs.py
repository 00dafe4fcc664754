"""Robot logs as loggers write them: epoch time stamps (rounded by float64), a clock
that jitters within 1 %, and what must still be refused (a gap, time running back, a
word in a number column), each named by its line."""
from __future__ import annotations

import numpy as np
import pytest

from harness.cli import main
from harness.robot.examples import example_urdf
from harness.robot.pipeline import LogError, read_log
from harness.robot.urdf import read_urdf

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


@pytest.fixture(scope="module")
def arm():
    path, _ = example_urdf("double_pendulum")
    return path, read_urdf(path)


def _log(path, t, seconds: float = 6.0):
    """A slow two-joint swing with its gravity torques: enough to identify a payload."""
    q = np.column_stack([0.8 * np.sin(1.3 * (t - t[0])), 0.6 * np.sin(2.1 * (t - t[0]))])
    u = np.column_stack([5.0 * np.sin(1.3 * (t - t[0])), 2.0 * np.cos(2.1 * (t - t[0]))])
    np.savetxt(path, np.column_stack([t, q, u]), delimiter=",", header="t,q1,q2,u1,u2",
               comments="", fmt="%.17g")
    return path


def test_epoch_time_stamps_at_1_khz_are_accepted(tmp_path, arm):
    t = 1.7e9 + np.arange(6000) * 1e-3  # float64 rounds these steps by up to 2.4e-7 s
    steps = np.diff(t)
    assert steps.max() - steps.min() > 1e-7  # what a 1e-6 relative tolerance refused
    log = read_log(_log(tmp_path / "epoch.csv", t), 2)
    assert log.step == pytest.approx(1e-3, rel=1e-7)  # the stamps resolve 2.4e-7 s
    assert log.t[0] == t[0]  # the stamps as written


def test_a_clock_jittering_within_one_percent_is_used_as_it_is(tmp_path):
    rng = np.random.default_rng(3)
    t = np.arange(6000) * 1e-3 + rng.uniform(-4e-6, 4e-6, 6000)
    log = read_log(_log(tmp_path / "jitter.csv", t), 2)
    assert log.step == pytest.approx(1e-3, rel=1e-5)


@pytest.mark.parametrize("change, message", [
    (lambda t: np.concatenate([t[:3000], t[3000:] + 0.05]), "line 3002: a step of 0.051 s"),
    (lambda t: np.concatenate([t[:100], t[99:100], t[101:]]), "line 102: t does not increase"),
])
def test_gaps_and_time_running_back_are_refused_with_their_line(tmp_path, change, message):
    t = change(np.arange(6000) * 1e-3)
    with pytest.raises(LogError, match=message):
        read_log(_log(tmp_path / "bad.csv", t), 2)


def test_a_word_in_a_number_column_is_named_with_its_line(tmp_path, arm, capsys):
    urdf, _ = arm
    path = _log(tmp_path / "word.csv", np.arange(6000) * 1e-3)
    lines = path.read_text().splitlines()
    lines[50] = lines[50].split(",", 1)[0] + ",abc," + lines[50].split(",", 2)[2]
    path.write_text("\n".join(lines) + "\n")
    assert main(["identify", str(path), "--robot", str(urdf), "--out", str(tmp_path / "o")]) == 2
    assert "line 51: q1 is not a number" in capsys.readouterr().err


def test_a_file_without_a_header_has_the_roles_in_order(tmp_path):
    path = _log(tmp_path / "plain.csv", np.arange(6000) * 1e-3)
    path.write_text("\n".join(path.read_text().splitlines()[1:]) + "\n")  # the header gone
    log = read_log(path, 2)
    assert log.q.shape == (6000, 2) and log.t[0] == 0.0
    with pytest.raises(LogError, match="no header row and 5 columns; a robot of 3 joints"):
        read_log(path, 3)


def test_columns_by_number_in_the_robots_own_order(tmp_path):
    t = np.arange(6000) * 1e-3
    path = _log(tmp_path / "log.csv", t)
    plain = read_log(path, 2)
    # the robot's own order: u2, q2, t, u1, q1, without a header row
    rows = np.loadtxt(path, delimiter=",", skiprows=1)[:, [4, 2, 0, 3, 1]]
    shuffled = tmp_path / "shuffled.csv"
    np.savetxt(shuffled, rows, delimiter=",", fmt="%.17g")
    log = read_log(shuffled, 2, {"t": "3", "q1": "5", "q2": "2", "u1": "4", "u2": "1"})
    assert np.array_equal(log.q, plain.q) and np.array_equal(log.u, plain.u)
    with pytest.raises(LogError, match="no column '9'"):
        read_log(shuffled, 2, {"t": "9", "q1": "5", "q2": "2", "u1": "4", "u2": "1"})
