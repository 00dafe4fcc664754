"""Logs without samples: a CSV of its header row only (with or without blank lines or a
final line feed) says so as an empty Parquet file does, with one message on the robot
and the model-file paths and exit status 2.  Logs without an end or a form: a link to a
device or a FIFO (refused unread) and a header row that never ends
are each named, exit status 2, never a traceback, a wait or MemoryError.
(The malformed .mat files: test_mat_file_malformed.py.)
"""
from __future__ import annotations

import os
import resource
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from cli_runner import FMU_DIR, REPO, cli, refused

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


EMPS = REPO / "examples" / "emps" / "emps.toml"  # columns t, qm, vir


@pytest.fixture(scope="module")
def urdf() -> Path:
    from harness.robot.examples import example_urdf
    return Path(example_urdf("double_pendulum")[0])


def message(text: str, path: Path) -> str:
    """The error line, the file's name taken out (to compare two files' messages)."""
    line = [row for row in text.splitlines() if str(path) in row][-1]
    return line.replace(str(path), "LOG")


def empty_parquet(path: Path, columns: list[str]) -> Path:
    import pyarrow as pa
    import pyarrow.parquet as pq
    pq.write_table(pa.table({c: np.array([], float) for c in columns}), path)
    return path


@pytest.mark.parametrize("tail", ["\n", "", "\n\n\n"])
@pytest.mark.parametrize("command", ["identify", "validate"])
def test_a_robot_log_of_its_header_only_has_no_samples(tmp_path, urdf, command, tail):
    columns = ["t", "q1", "q2", "u1", "u2"]
    log = tmp_path / "log.csv"
    log.write_text(",".join(columns) + tail)
    code, text = cli([command, str(log), "--robot", str(urdf), "--out", str(tmp_path / "o")])
    assert code == 2, text
    refused(code, text, str(log), "0 samples")
    assert "not a number" not in text and "line 0" not in text
    parquet = empty_parquet(tmp_path / "log.parquet", columns)
    code, other = cli([command, str(parquet), "--robot", str(urdf), "--out",
                       str(tmp_path / "o")])
    assert code == 2 and message(other, parquet) == message(text, log)


@pytest.mark.parametrize("command", ["identify", "validate"])
def test_a_model_log_of_its_header_only_has_no_samples(tmp_path, command):
    log = tmp_path / "log.csv"
    log.write_text("t,qm,vir\n")
    code, text = cli([command, str(log), "--model", str(EMPS), "--out", str(tmp_path / "o")])
    assert code == 2, text
    refused(code, text, str(log), "0 samples")
    parquet = empty_parquet(tmp_path / "log.parquet", ["t", "qm", "vir"])
    code, other = cli([command, str(parquet), "--model", str(EMPS), "--out",
                       str(tmp_path / "o")])
    assert code == 2 and message(other, parquet) == message(text, log)


def test_the_column_reader_gives_no_rows_for_a_header_only_file(tmp_path):
    from harness.csv_columns import read_columns, read_header

    log = tmp_path / "log.csv"
    log.write_text("t,y\n")
    data = read_columns(log, read_header(log), ["t", "y"], ["t", "y"])
    assert data.shape == (0, 2)


def _limited() -> None:
    """The child's address space: a reader without a cap fails, not the machine."""
    resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))


# every command that reads a log: its arguments after the log (URDF: the robot's)
READERS = {
    "identify --robot": ["identify", "--robot", "URDF"],
    "identify --model": ["identify", "--model", str(EMPS)],
    "identify (t, y, u)": ["identify"],
    "validate --robot": ["validate", "--robot", "URDF"],
    "validate --model": ["validate", "--model", str(EMPS)],
}


@pytest.mark.parametrize("kind", ["device", "fifo"])
@pytest.mark.parametrize("reader", list(READERS))
def test_a_log_that_is_not_a_regular_file_is_refused_unread(tmp_path, urdf, reader, kind):
    """A link to /dev/zero (no end: the header was read until MemoryError) or a FIFO (no
    writer: the reader waited for ever) as the log: refused by its mode, naming it."""
    log = tmp_path / "log.csv"
    if kind == "device":
        log.symlink_to(os.devnull.replace("null", "zero"))  # read only, never written
    else:
        os.mkfifo(log)
    command, *rest = [str(urdf) if a == "URDF" else a for a in READERS[reader]]
    result = subprocess.run([sys.executable, "-m", "harness", "--fmu-dir", str(FMU_DIR),
                             command, str(log), *rest, "--out", str(tmp_path / "out")],
                            cwd=REPO, capture_output=True, text=True, timeout=60,
                            preexec_fn=_limited)
    refused(result.returncode, result.stderr, str(log), "not a regular file",
            "character device" if kind == "device" else "FIFO")
    assert result.returncode == 2 and not (tmp_path / "out").exists(), result.stderr[-2000:]


def test_a_header_row_that_never_ends_is_refused_after_a_cap(tmp_path, urdf):
    from harness.log_columns import MAX_HEADER_BYTES

    log = tmp_path / "log.csv"
    log.write_bytes(b"t" * (MAX_HEADER_BYTES + 10))
    for args in (["--robot", str(urdf)], ["--model", str(EMPS)], []):
        code, text = cli(["identify", str(log), *args, "--out", str(tmp_path / "o")])
        assert code == 2, text
        refused(code, text, str(log), f"does not end within {MAX_HEADER_BYTES} bytes")
