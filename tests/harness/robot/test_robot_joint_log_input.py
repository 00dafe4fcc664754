"""Robot logs as loggers write them: epoch time stamps (rounded by float64), a clock
that jitters within 1 % (used as it is) or more (resampled, and said so), and what must
still be refused (a gap, time running back, a word in a number column), each named by
its line.  A robot's --columns name only the robot's roles (harness/robot/joint_log.py).
"""
from __future__ import annotations

import numpy as np
import pytest
from cli_runner import cli, refused
from robot_helpers import swing_log

from harness.cli import main
from harness.robot.examples import example_urdf
from harness.robot.joint_log import LogError, read_log
from harness.robot.urdf import read_urdf

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


@pytest.fixture(scope="module")
def arm():
    path, _ = example_urdf("double_pendulum")
    return path, read_urdf(path)


def test_epoch_time_stamps_at_1_khz_are_accepted(tmp_path, arm):
    t = 1.7e9 + np.arange(6000) * 1e-3  # float64 rounds these steps by up to 2.4e-7 s
    steps = np.diff(t)
    assert steps.max() - steps.min() > 1e-7  # what a 1e-6 relative tolerance refused
    log = read_log(swing_log(tmp_path / "epoch.csv", t), 2)
    assert log.step == pytest.approx(1e-3, rel=1e-7)  # the stamps resolve 2.4e-7 s
    assert log.t[0] == t[0]  # the stamps as written


def test_a_clock_jittering_within_one_percent_is_used_as_it_is(tmp_path):
    rng = np.random.default_rng(3)
    t = np.arange(6000) * 1e-3 + rng.uniform(-4e-6, 4e-6, 6000)
    log = read_log(swing_log(tmp_path / "jitter.csv", t), 2)
    assert log.step == pytest.approx(1e-3, rel=1e-5)


def test_a_real_time_loggers_clock_is_resampled_and_said_so(tmp_path, arm, capsys):
    """Steps of 8 to 13 ms (a real-time interface at about 94 Hz): the positions on even
    steps of the mean step by cubic splines, the torques linearly."""
    urdf, _ = arm
    rng = np.random.default_rng(5)
    t = np.concatenate([[0.0], np.cumsum(rng.uniform(0.008, 0.013, 1999))])
    path = swing_log(tmp_path / "rt.csv", t)
    log = read_log(path, 2)
    assert log.resampled and "resampled onto even steps" in log.resampled
    assert np.allclose(np.diff(log.t), log.step, rtol=1e-9)
    truth = 0.8 * np.sin(1.3 * log.t)
    assert np.max(np.abs(log.q[:, 0] - truth)) < 1e-7  # measured 2.7e-10
    assert main(["identify", str(path), "--robot", str(urdf), "--unknown", "payload",
                 "--out", str(tmp_path / "o")]) in (0, 1)
    assert "the clock jitters (steps from 0.008" in capsys.readouterr().out


@pytest.mark.parametrize("change, message", [
    (lambda t: np.concatenate([t[:3000], t[3000:] + 0.05]), "line 3002: a gap of 0.051 s"),
    (lambda t: np.concatenate([t[:100], t[99:100], t[101:]]), "line 102: t does not increase"),
])
def test_gaps_and_time_running_back_are_refused_with_their_line(tmp_path, change, message):
    t = change(np.arange(6000) * 1e-3)
    with pytest.raises(LogError, match=message):
        read_log(swing_log(tmp_path / "bad.csv", t), 2)


def test_a_word_in_a_number_column_is_named_with_its_line(tmp_path, arm, capsys):
    urdf, _ = arm
    path = swing_log(tmp_path / "word.csv", np.arange(6000) * 1e-3)
    lines = path.read_text().splitlines()
    lines[50] = lines[50].split(",", 1)[0] + ",abc," + lines[50].split(",", 2)[2]
    path.write_text("\n".join(lines) + "\n")
    assert main(["identify", str(path), "--robot", str(urdf), "--out", str(tmp_path / "o")]) == 2
    assert "line 51: q1 is not a number" in capsys.readouterr().err


def test_a_file_without_a_header_has_the_roles_in_order(tmp_path):
    path = swing_log(tmp_path / "plain.csv", np.arange(6000) * 1e-3)
    path.write_text("\n".join(path.read_text().splitlines()[1:]) + "\n")  # the header gone
    log = read_log(path, 2)
    assert log.q.shape == (6000, 2) and log.t[0] == 0.0
    with pytest.raises(LogError, match="no header row and 5 columns; a robot of 3 joints"):
        read_log(path, 3)


def test_columns_by_number_in_the_robots_own_order(tmp_path):
    t = np.arange(6000) * 1e-3
    path = swing_log(tmp_path / "log.csv", t)
    plain = read_log(path, 2)
    # the robot's own order: u2, q2, t, u1, q1, without a header row
    rows = np.loadtxt(path, delimiter=",", skiprows=1)[:, [4, 2, 0, 3, 1]]
    shuffled = tmp_path / "shuffled.csv"
    np.savetxt(shuffled, rows, delimiter=",", fmt="%.17g")
    log = read_log(shuffled, 2, {"t": "3", "q1": "5", "q2": "2", "u1": "4", "u2": "1"})
    assert np.array_equal(log.q, plain.q) and np.array_equal(log.u, plain.u)
    with pytest.raises(LogError, match="no column '9'"):
        read_log(shuffled, 2, {"t": "9", "q1": "5", "q2": "2", "u1": "4", "u2": "1"})


def _frame(t):
    import pandas as pd
    q = np.column_stack([0.8 * np.sin(1.3 * t), 0.6 * np.sin(2.1 * t)])
    u = np.column_stack([5.0 * np.sin(1.3 * t), 2.0 * np.cos(2.1 * t)])
    return pd.DataFrame({"t": t, "q1": q[:, 0], "q2": q[:, 1], "u1": u[:, 0], "u2": u[:, 1]})


@pytest.mark.parametrize("command", ["identify", "validate"])
@pytest.mark.parametrize("name", ["log.xlsx", "log.json", "log", "log.csv.gz"])
def test_other_formats_exit_2_naming_the_file_and_the_formats(tmp_path, arm, command, name):
    from cli_runner import cli, refused
    urdf, _ = arm
    data = tmp_path / name
    swing_log(data, np.arange(6000) * 1e-3)  # CSV text, whatever the name says
    code, text = cli([command, str(data), "--robot", str(urdf), "--out", str(tmp_path / "o")])
    assert code == 2, text
    refused(code, text, str(data), "CSV (.csv, .txt), Parquet (.parquet, .pq), MATLAB (.mat)")


def test_a_parquet_log_reads_as_its_csv_and_its_problems_are_named(tmp_path, arm):
    frame = _frame(np.arange(6000) * 1e-3)
    frame.to_parquet(tmp_path / "log.parquet")
    frame.to_csv(tmp_path / "log.csv", index=False, float_format="%.17g")
    parquet, text = read_log(tmp_path / "log.parquet", 2), read_log(tmp_path / "log.csv", 2)
    for a, b in ((parquet.t, text.t), (parquet.q, text.q), (parquet.u, text.u)):
        assert np.array_equal(a, b)
    # integer time stamps in ns, a float32 column: numbers of any numeric type
    stamps = frame.assign(t=np.arange(6000, dtype=np.int64) * 1_000_000,
                          q2=frame.q2.astype(np.float32))
    stamps.to_parquet(tmp_path / "ns.pq")
    from harness.robot.log_units import log_units
    log = read_log(tmp_path / "ns.pq", 2, units=log_units(["revolute"] * 2, time="ns"))
    assert log.step == pytest.approx(1e-3, rel=1e-12)
    assert np.allclose(log.q[:, 1], frame.q2, rtol=1e-6, atol=1e-7)
    # a missing value, a column of words, a column not there, a file that is no Parquet
    frame.assign(q2=frame.q2.where(frame.index != 41)).to_parquet(tmp_path / "null.parquet")
    with pytest.raises(LogError, match=r"null.parquet row 42: q2 is NaN"):
        read_log(tmp_path / "null.parquet", 2)
    frame.assign(u1=frame.u1.astype(str)).to_parquet(tmp_path / "words.parquet")
    with pytest.raises(LogError, match=r"words.parquet: column 'u1' \(u1\) holds (large_)?string, not numbers"):
        read_log(tmp_path / "words.parquet", 2)
    with pytest.raises(LogError, match=r"no column 'q3'.*found: t, q1, q2, u1, u2"):
        read_log(tmp_path / "log.parquet", 2, {"q2": "q3"})
    (tmp_path / "fake.parquet").write_text("t,q1\n0,1\n")
    with pytest.raises(LogError, match=r"fake.parquet: not a readable Parquet file"):
        read_log(tmp_path / "fake.parquet", 2)
    with pytest.raises(LogError, match=r"absent.parquet: cannot open"):
        read_log(tmp_path / "absent.parquet", 2)


def test_a_log_in_ms_read_as_seconds_is_warned_of(tmp_path, arm):
    from cli_runner import cli
    urdf, _ = arm
    data = swing_log(tmp_path / "ms.csv", np.arange(6000) * 1.0)  # ms, no --time-unit
    code, text = cli(["identify", str(data), "--robot", str(urdf), "--out", str(tmp_path / "o"),
                      "--unknown", "payload"])
    # read as seconds the swing is a thousand times slower: too slow for the friction
    assert code == 2 and "samples 1 s apart" in text and "--time-unit ms" in text, text
    code, text = cli(["validate", str(data), "--robot", str(urdf), "--out", str(tmp_path / "v")])
    assert code == 1 and "samples 1 s apart" in text and "--time-unit ms" in text, text
    code, text = cli(["validate", str(data), "--robot", str(urdf), "--out", str(tmp_path / "w"),
                      "--time-unit", "s"])  # seconds confirmed: no warning
    assert code == 0 and "apart" not in text, text


@pytest.mark.parametrize("command", ["identify", "validate"])
@pytest.mark.parametrize("scale", [1e13, 1e200, 1e307])
def test_torques_too_large_for_any_joint_exit_2_naming_the_column(tmp_path, arm, command, scale):
    """Torques scaled far beyond any joint's (a wrong unit or gain): the regression's sums
    would overflow (singular normal equations, non-finite whitening, a figure that cannot
    be drawn); refused by the reader, naming the column."""
    from cli_runner import cli, refused
    urdf, _ = arm
    t = np.arange(6000) * 1e-3
    data = swing_log(tmp_path / "log.csv", t)
    values = np.loadtxt(data, delimiter=",", skiprows=1)
    values[:, 3] *= scale
    np.savetxt(data, values, delimiter=",", header="t,q1,q2,u1,u2", comments="", fmt="%.17g")
    out = tmp_path / "out"
    code, text = cli([command, str(data), "--robot", str(urdf), "--out", str(out)])
    assert code == 2, text
    refused(code, text, "u1 reaches", "beyond 1e+12")
    assert not out.exists()


def test_robot_columns_name_only_the_robots_roles(tmp_path):
    from harness.robot.examples import example_urdf
    urdf, _ = example_urdf("double_pendulum")
    t = np.arange(3000) * 1e-3
    np.savetxt(tmp_path / "log.csv", np.column_stack([t, np.sin(t), np.cos(t), t, t]),
               delimiter=",", header="t,q1,q2,u1,u2", comments="")
    for command in ("identify", "validate"):
        code, text = cli([command, str(tmp_path / "log.csv"), "--robot", str(urdf), "--out",
                          str(tmp_path / command), "--columns", "q3=q1"])
        assert code == 2, text
        refused(code, text, "'q3'", "roles: t, q1, q2, u1, u2")
