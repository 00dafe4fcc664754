"""The one log reader: the same signals from CSV, Parquet and MATLAB, a stated sample
rate in place of a time column, and every problem named with its file and place."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import scipy.io

from harness.log_signals import Column, LogSignalsError, read_signals

POSITION, INPUT = [Column("x", "pos")], [Column("u", "force")]


def _frame(samples: int = 200) -> pd.DataFrame:
    t = np.arange(samples) * 1e-3
    return pd.DataFrame({"time": t, "pos": np.sin(t), "force": np.cos(t)})


def test_csv_parquet_and_matlab_give_the_same_signals(tmp_path):
    frame = _frame()
    frame.to_csv(tmp_path / "log.csv", index=False, float_format="%.17g")
    frame.to_parquet(tmp_path / "log.parquet")
    scipy.io.savemat(tmp_path / "log.mat", {k: frame[k].to_numpy() for k in frame})
    read = [read_signals(tmp_path / name, Column("t", "time"), POSITION, INPUT)
            for name in ("log.csv", "log.parquet", "log.mat")]
    for other in read[1:]:
        for a, b in ((read[0].t, other.t), (read[0].q, other.q),
                     (read[0].inputs, other.inputs)):
            assert np.array_equal(a, b)
    assert read[0].step == pytest.approx(1e-3, rel=1e-12) and read[0].resampled is None


def test_a_sample_rate_replaces_the_time_column(tmp_path):
    frame = _frame().drop(columns="time")
    scipy.io.savemat(tmp_path / "log.mat", {k: frame[k].to_numpy() for k in frame})
    signals = read_signals(tmp_path / "log.mat", None, POSITION, INPUT, sample_rate=500.0)
    assert signals.step == pytest.approx(2e-3, rel=1e-12) and signals.t[0] == 0.0
    with pytest.raises(ValueError, match="one of the two"):
        read_signals(tmp_path / "log.mat", Column("t", "time"), POSITION, INPUT,
                     sample_rate=500.0)


def test_factors_scale_the_positions_and_inputs(tmp_path):
    _frame().to_csv(tmp_path / "log.csv", index=False)
    plain = read_signals(tmp_path / "log.csv", Column("t", "time"), POSITION, INPUT)
    scaled = read_signals(tmp_path / "log.csv", Column("t", "time"), POSITION, INPUT,
                          time_factor=1e-3, factors=np.array([2.0, -1.0]))
    assert np.allclose(scaled.t, 1e-3 * plain.t) and np.allclose(scaled.q, 2 * plain.q)
    assert np.allclose(scaled.inputs, -plain.inputs)


@pytest.mark.parametrize("name,expected", [
    ("log.csv", "log.csv line 12: x (column 'pos') is NaN, infinite or missing"),
    ("log.parquet", "log.parquet row 11: x (column 'pos') is NaN"),
    ("log.mat", "log.mat at sample 11: x (column 'pos') is NaN"),
])
def test_a_non_finite_value_is_named_with_its_place(tmp_path, name, expected):
    frame = _frame()
    frame.loc[10, "pos"] = np.inf
    path = tmp_path / name
    if name.endswith(".csv"):
        frame.to_csv(path, index=False)
    elif name.endswith(".parquet"):
        frame.to_parquet(path)
    else:
        scipy.io.savemat(path, {k: frame[k].to_numpy() for k in frame})
    with pytest.raises(LogSignalsError) as error:
        read_signals(path, Column("t", "time"), POSITION, INPUT)
    assert expected in str(error.value)


def test_missing_columns_short_logs_and_other_formats_are_named(tmp_path):
    _frame().to_csv(tmp_path / "log.csv", index=False)
    with pytest.raises(LogSignalsError, match=r"no column 'speed' for v \(found: time, pos, "
                                              r"force\); map it"):
        read_signals(tmp_path / "log.csv", Column("t", "time"), [Column("v", "speed")], INPUT,
                     missing_hint="; map it")
    _frame(5).to_csv(tmp_path / "short.csv", index=False)
    with pytest.raises(LogSignalsError, match="5 samples; identification needs many more"):
        read_signals(tmp_path / "short.csv", Column("t", "time"), POSITION, INPUT)
    (tmp_path / "log.xlsx").write_text("x")
    with pytest.raises(LogSignalsError, match=r"MATLAB \(\.mat\)"):
        read_signals(tmp_path / "log.xlsx", Column("t", "time"), POSITION, INPUT)
    for text in ("t,pos,force\n0,1,2\n", ""):  # a text file named .mat, an empty one
        (tmp_path / "text.mat").write_text(text)
        with pytest.raises(LogSignalsError, match="not a readable MATLAB file"):
            read_signals(tmp_path / "text.mat", Column("t", "time"), POSITION, INPUT)


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_a_column_name_given_twice_in_the_header_is_refused(tmp_path, suffix):
    """Which of two columns of one name is meant cannot be told: neither is guessed."""
    frame = _frame()
    frame.insert(2, "dup", frame["pos"] * 0.0)
    frame.columns = ["time", "pos", "pos", "force"]
    path = tmp_path / f"log{suffix}"
    if suffix == ".csv":
        frame.to_csv(path, index=False)
    else:
        import pyarrow as pa
        import pyarrow.parquet as pq
        pq.write_table(pa.Table.from_arrays([pa.array(frame.iloc[:, i]) for i in range(4)],
                                            names=list(frame.columns)), path)
    with pytest.raises(LogSignalsError, match=r"names 'pos' \(x\) more than once "
                                              r"\(columns 2, 3\)"):
        read_signals(path, Column("t", "time"), POSITION, INPUT)


@pytest.mark.parametrize("value, said", [
    ("1_000", r"line 12: u is not a number"),  # Python's float() reads it, pandas does not
    ("x" * 200_000, r"line 12: a field longer than 131072 characters is not a number"),
])
def test_a_bad_value_is_named_with_its_line_and_a_bounded_message(tmp_path, value, said):
    lines = _frame(50).to_csv(index=False).splitlines()
    lines[5] = lines[5].rsplit(",", 1)[0] + ","  # an empty value before it: read as NaN
    lines[11] = lines[11].rsplit(",", 1)[0] + "," + value
    path = tmp_path / "log.csv"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(LogSignalsError, match=said) as error:
        read_signals(path, Column("t", "time"), POSITION, INPUT)
    assert len(str(error.value)) < 600
