"""identify on a t, y, u log in Parquet: the same samples, stamps and estimates as the
same log in CSV, its problems named with their row; other extensions refused."""
from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from harness.cli import main
from harness.recording import DataError, ReadOptions, parse_columns, read_recording


def _frame(t, names=("t", "y", "u")) -> pd.DataFrame:
    seconds = np.asarray(t, dtype=float)
    seconds = seconds - seconds[0]
    return pd.DataFrame({names[0]: t, names[1]: 0.1 * np.sin(3 * seconds),
                         names[2]: np.cos(2 * seconds)})


def _both(tmp_path, frame, name="log"):
    # each number as its shortest round-trip decimal, the text Parquet's stamps become
    frame.to_csv(tmp_path / f"{name}.csv", index=False)
    frame.to_parquet(tmp_path / f"{name}.parquet")
    return tmp_path / f"{name}.csv", tmp_path / f"{name}.parquet"


@pytest.mark.parametrize("t, unit", [
    (np.arange(3000) * 1e-3, None),
    (1.7e9 + np.arange(3000) * 1e-3, None),                # epoch seconds
    (np.arange(3000, dtype=np.int64) * 1_000_000, "ns"),   # integer nanoseconds
    (np.arange(3000) * 1.0, "ms"),
])
def test_parquet_gives_the_samples_of_the_csv(tmp_path, t, unit):
    csv_log, parquet_log = _both(tmp_path, _frame(t, ("time", "theta", "tau")))
    options = ReadOptions(columns=parse_columns("y=theta,u=tau"), time_unit=unit)
    a, b = read_recording(csv_log, options), read_recording(parquet_log, options)
    for x, y in ((a.t, b.t), (a.y, b.y), (a.u, b.u)):
        np.testing.assert_array_equal(x, y)
    assert b.step == pytest.approx(1e-3, rel=1e-4)  # epoch stamps: float64 rounds t to 2.4e-7 s


def test_parquet_problems_are_named_with_their_row(tmp_path):
    frame = _frame(np.arange(3000) * 1e-3)
    frame.assign(y=frame.y.where(frame.index != 41)).to_parquet(tmp_path / "nan.parquet")
    with pytest.raises(DataError, match=r"nan.parquet row 42: y is missing or not finite"):
        read_recording(tmp_path / "nan.parquet")
    back = frame.assign(t=np.where(frame.index == 100, 0.05, frame.t))
    back.to_parquet(tmp_path / "back.parquet")
    with pytest.raises(DataError, match=r"back.parquet row 101: time does not increase"):
        read_recording(tmp_path / "back.parquet")
    frame.assign(u=frame.u.astype(str)).to_parquet(tmp_path / "words.parquet")
    with pytest.raises(DataError, match=r"column 'u' \(u\) holds (large_)?string"):
        read_recording(tmp_path / "words.parquet")
    with pytest.raises(DataError, match=r"missing column\(s\) y"):
        frame.rename(columns={"y": "theta"}).to_parquet(tmp_path / "names.parquet")
        read_recording(tmp_path / "names.parquet")
    (tmp_path / "fake.parquet").write_text("t,y,u\n0,0,0\n")
    with pytest.raises(DataError, match=r"fake.parquet: not a readable Parquet file"):
        read_recording(tmp_path / "fake.parquet")


@pytest.mark.parametrize("name", ["log.xlsx", "log.mat", "log.json", "log"])
def test_other_extensions_are_refused_naming_the_file_and_the_formats(tmp_path, name):
    path = tmp_path / name
    _frame(np.arange(100) * 1e-3).to_csv(path, index=False)  # CSV text, whatever the name
    with pytest.raises(DataError, match=r"logs are read as CSV \(.csv, .txt\), Parquet"):
        read_recording(path)


def test_identify_writes_the_same_estimates_from_parquet(tmp_path, observer_fmu):
    csv_log, parquet_log = _both(tmp_path, _frame(1.7e9 + np.arange(3000) * 1e-3))
    found, stamps = {}, {}
    for log in (csv_log, parquet_log):
        out = tmp_path / log.suffix[1:]
        assert main(["identify", str(log), "--out", str(out), "--fmu-dir",
                     str(observer_fmu.parent)]) == 0
        found[log.suffix] = json.loads((out / "estimates.json").read_text())
        stamps[log.suffix] = pd.read_csv(out / "estimates.csv", dtype={"t": str}).t
    assert found[".csv"]["final"] == found[".parquet"]["final"]
    # the stamps written back as each file holds them: the CSV's text, every digit, and
    # the Parquet file's numbers as their shortest decimals ("1700000001" where the CSV
    # file has "1700000001.0")
    assert found[".csv"]["first_stamp"] == "1700000000.0"
    assert found[".parquet"]["first_stamp"] == "1700000000"
    csv_stamps, parquet_stamps = stamps[".csv"], stamps[".parquet"]
    assert np.array_equal(csv_stamps.astype(float), parquet_stamps.astype(float))
    different = csv_stamps != parquet_stamps
    assert (csv_stamps[different] == parquet_stamps[different] + ".0").all()
    assert parquet_stamps.iloc[1] == "1700000000.001"
