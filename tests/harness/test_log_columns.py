"""harness.log_columns and harness.csv_columns: a log's format by its extension, its
header (or column numbers), its columns as floats, and what is refused before reading."""
from __future__ import annotations

import os
import warnings

import numpy as np
import pandas as pd
import pytest

from harness.log_columns import (
    MAX_HEADER_BYTES,
    LogColumnError,
    check_column_roles,
    column_of,
    log_format,
    mean_step,
    read_columns,
    read_header,
    uneven_step,
)


def test_the_format_is_told_by_the_extension(tmp_path):
    for name, kind in (("a.csv", "csv"), ("a.TXT", "csv"), ("a.pq", "parquet")):
        (tmp_path / name).write_text("t\n0\n")
        assert log_format(tmp_path / name) == kind
    (tmp_path / "a.xlsx").write_text("")
    with pytest.raises(LogColumnError, match=r"a \.xlsx file; logs are read as CSV \(\.csv, "
                                             r"\.txt\), Parquet \(\.parquet, \.pq\)"):
        log_format(tmp_path / "a.xlsx")


def test_special_files_and_endless_header_rows_are_refused_unread(tmp_path):
    fifo = tmp_path / "log.csv"
    os.mkfifo(fifo)
    with pytest.raises(LogColumnError, match=r"a FIFO \(named pipe\), not a regular file"):
        log_format(fifo)  # opening it would wait for a writer
    long = tmp_path / "long.csv"
    long.write_bytes(b"t" * (MAX_HEADER_BYTES + 1))
    with pytest.raises(LogColumnError, match="does not end within"):
        log_format(long)


def test_a_header_or_column_numbers(tmp_path):
    named = tmp_path / "named.csv"
    named.write_text("\ufefftime, pos ,force\n0,1,2\n")
    header = read_header(named)
    assert list(header) == ["time", "pos", "force"] and header.present
    assert column_of(header, "pos") == "pos" and column_of(header, "3") == "force"
    assert column_of(header, "4") is None and column_of(header, "speed") is None
    bare = tmp_path / "bare.csv"
    bare.write_text("0,1,2\n1,2,3\n")
    header = read_header(bare)
    assert list(header) == ["1", "2", "3"] and not header.present


def test_columns_read_alike_from_csv_and_parquet(tmp_path):
    frame = pd.DataFrame({"t": [0.0, 0.5, 1.0], "q": [1.0, np.nan, 3.0], "n": [1, 2, 3]})
    frame.to_csv(tmp_path / "l.csv", index=False)
    frame.to_parquet(tmp_path / "l.parquet")
    for name in ("l.csv", "l.parquet"):
        header = read_header(tmp_path / name)
        data = read_columns(tmp_path / name, header, ["n", "q"], ["u", "x"])
        np.testing.assert_array_equal(data, [[1, 1], [2, np.nan], [3, 3]])


def test_text_in_a_parquet_column_is_named(tmp_path):
    pd.DataFrame({"t": [0.0, 1.0], "q": ["a", "b"]}).to_parquet(tmp_path / "l.parquet")
    header = read_header(tmp_path / "l.parquet")
    with pytest.raises(LogColumnError, match=r"column .q. \(x\) holds (large_)?string, not numbers"):
        read_columns(tmp_path / "l.parquet", header, ["q"], ["x"])


@pytest.mark.parametrize("text, said", [("q1=a,q1=b", "gives q1 twice"),
                                        ("q1=a,q2=a", "maps q1 and q2 to the same column")])
def test_column_roles_given_twice_are_refused(text, said):
    with pytest.raises(LogColumnError, match=said):
        check_column_roles(text)


def test_steps():
    t = np.array([1e9, 1e9 + 0.01, 1e9 + 0.02, 1e9 + 0.03])
    assert mean_step(t) == pytest.approx(0.01, rel=1e-6)
    assert uneven_step(t, 0.01) is None
    index, said = uneven_step(np.array([0.0, 0.01, 0.03, 0.04]), 0.01)
    assert index == 2 and "a step of 0.02 s where the mean step is" in said
    index, said = uneven_step(np.array([0.0, 0.01, 0.01]), 0.01)
    assert index == 2 and "does not increase" in said


@pytest.mark.cli
def test_the_mean_step_of_extreme_times_does_not_overflow():
    from harness.log_columns import mean_step
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert mean_step(np.array([-1.7e308, 0.0, 1.7e308])) == 1.7e308
        assert mean_step(np.array([-1.7e308, 1.7e308])) == np.inf


def test_distinct_columns_refuse_a_repeated_name_and_a_shared_column():
    from harness.log_columns import LogColumnError, check_distinct_columns
    header = ["t", "Pos", "pos ", "u"]
    check_distinct_columns("log.csv", header, [("t", 0), ("y", 1), ("u", 3)])  # exact names
    with pytest.raises(LogColumnError, match=r"log.csv line 1: the header names 'Pos' \(y\) "
                                             r"more than once \(columns 2, 3\)"):
        check_distinct_columns("log.csv line 1", header, [("y", 1)],
                               key=lambda name: name.strip().lower())
    with pytest.raises(LogColumnError, match="y and u are both read from the column 'u'"):
        check_distinct_columns("log.csv", header, [("t", 0), ("y", 3), ("u", 3)])
