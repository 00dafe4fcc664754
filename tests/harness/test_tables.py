"""harness.tables: the CSV (or Parquet) files of columns the tools write."""
from __future__ import annotations

import numpy as np
import pyarrow.parquet as pq

from harness.tables import CsvStream, csv_name, write_csv


def test_fmi_array_names_become_csv_column_names():
    assert csv_name("theta_hat[1,2]") == "theta_hat[1][2]"
    assert csv_name("x1_hat") == "x1_hat"


def test_a_table_round_trips_every_digit(tmp_path):
    values = np.array([0.1, 1 / 3, 1e-300, -2.5e300])
    path = write_csv(tmp_path / "t.csv", {"a[1,1]": values, "b": values * 2})
    lines = path.read_text().splitlines()
    assert lines[0] == '"a[1][1]","b"'
    read = np.array([[float(x) for x in line.split(",")] for line in lines[1:]])
    np.testing.assert_array_equal(read[:, 0], values)


def test_a_stream_writes_its_blocks_in_order_as_csv_or_parquet(tmp_path):
    for name in ("s.csv", "s.parquet"):
        with CsvStream(tmp_path / name) as stream:
            for start in (0, 3):
                stream.write({"k": np.arange(start, start + 3, dtype=float)})
        if name.endswith(".csv"):
            rows = (tmp_path / name).read_text().splitlines()[1:]
            assert [float(r) for r in rows] == [0, 1, 2, 3, 4, 5]
        else:
            assert pq.read_table(tmp_path / name).column("k").to_pylist() == [0, 1, 2, 3, 4, 5]


def test_a_stream_writes_the_text_of_the_plain_writer_runs_of_equal_values_or_not(tmp_path):
    rng = np.random.default_rng(1)
    changing = rng.normal(size=12) * 10.0 ** rng.integers(-30, 30, size=12)
    runs = np.repeat([0.0, -0.0, 1 / 3, np.nan, np.inf, -np.inf, 1e-7, 1e21, 5e-324, 0.0],
                     [3, 2, 4, 2, 1, 1, 3, 2, 1, 5])
    blocks = [{"t": np.arange(24.0), "a[1,1]": runs[:24], "b": np.concatenate([changing] * 2)},
              {"t": np.arange(24.0, 36.0), "a[1,1]": changing, "b": runs[:12]},
              {"t": np.array([36.0]), "a[1,1]": np.array([-0.0]), "b": np.array([7.5])}]
    with CsvStream(tmp_path / "s.csv") as stream:
        for block in blocks:
            stream.write(block)
    whole = {k: np.concatenate([b[k] for b in blocks]) for k in blocks[0]}
    assert (tmp_path / "s.csv").read_bytes() == write_csv(tmp_path / "w.csv", whole).read_bytes()
