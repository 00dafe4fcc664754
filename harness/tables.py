"""CSV files the harness writes: a quoted header, every number at full precision.

Written by pyarrow's CSV writer: the header names are quoted, numbers are the
shortest text that reads back as the same double.  FMI names of 2-D array
elements hold a comma (``theta_hat[1,2]``); fmpy.util.read_csv splits the
header line at every comma, quoted or not, so such a name is written with the
indices in separate brackets (``theta_hat[1][2]``, :func:`csv_name`).  The
files then read the same with pandas.read_csv, the csv module and
fmpy.util.read_csv.
"""
from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any


def csv_name(name: str) -> str:
    """The column name of an FMI variable in the CSV files: ``a[1,2]`` -> ``a[1][2]``."""
    return name.replace(",", "][")


def _table(columns: Mapping[str, Any]):
    import pyarrow as pa

    return pa.table({csv_name(name): values for name, values in columns.items()})


def _options():
    import pyarrow.csv as pacsv

    # the header quoted; values never: they are numbers, or time stamps kept as written
    return pacsv.WriteOptions(quoting_style="none")


def write_csv(path: str | Path, columns: Mapping[str, Any]) -> Path:
    """Writes the columns (equal-length arrays; text columns as pyarrow strings) as CSV."""
    import pyarrow.csv as pacsv

    pacsv.write_csv(_table(columns), str(path), _options())
    return Path(path)


class CsvStream:
    """A CSV file written block by block (the columns of every block alike); a name
    ending in .parquet writes Parquet instead (4x faster to write than CSV: long logs)."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self._writer: Any = None  # a pyarrow Parquet or CSV writer once the first block came

    def write(self, columns: Mapping[str, Any]) -> None:
        import pyarrow.csv as pacsv

        table = _table(columns)
        if self._writer is None:
            if self.path.suffix == ".parquet":
                import pyarrow.parquet as pq

                # no dictionary encoding: measured values rarely repeat, and trying it
                # made writing 4x slower (bench/perf/identify_long_log.py)
                self._writer = pq.ParquetWriter(str(self.path), table.schema,
                                                use_dictionary=False)
            else:
                self._writer = pacsv.CSVWriter(str(self.path), table.schema,
                                               write_options=_options())
        self._writer.write_table(table)

    def close(self) -> None:
        if self._writer is not None:
            self._writer.close()
            self._writer = None

    def __enter__(self) -> CsvStream:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
