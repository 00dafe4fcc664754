"""Logs without samples: a CSV of its header row only (with or without blank lines or a
final line feed) says so as an empty Parquet file does, with one message on the robot
and the model-file paths and exit status 2."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from cli_runner import REPO, cli, refused

pytestmark = pytest.mark.cli

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
