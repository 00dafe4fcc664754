"""CSV files the harness writes: a quoted header, every number at full precision.

Written by pyarrow's CSV writer: the header names are quoted, numbers are the
shortest text that reads back as the same double.  FMI names of 2-D array
elements hold a comma (``theta_hat[1,2]``); fmpy.util.read_csv splits the
header line at every comma, quoted or not, so such a name is written with the
indices in separate brackets (``theta_hat[1][2]``, :func:`csv_name`).  The
files then read the same with pandas.read_csv, the csv module and
fmpy.util.read_csv.

A stream (:class:`CsvStream`, identify's estimates of long logs) turns its doubles
into text itself, with pyarrow's conversion, the one its CSV writer makes:
formatting the numbers is most of the cost of writing, and estimates that the
identifier updates now and then, or the zeros of unused coefficients, repeat for
thousands of rows, so each run of equal values is formatted once.  The bytes are
the writer's own.
"""
from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any


def csv_name(name: str) -> str:
    """The column name of an FMI variable in the CSV files: ``a[1,2]`` -> ``a[1][2]``."""
    return name.replace(",", "][")


def _table(columns: Mapping[str, Any]):
    import numpy as np
    import pyarrow as pa

    return pa.table({csv_name(name): as_arrow(values) if isinstance(values, np.ndarray)
                     and values.dtype == np.float64 and values.ndim == 1 else values
                     for name, values in columns.items()})


def _options():
    import pyarrow.csv as pacsv

    # the header quoted; values never: they are numbers, or time stamps kept as written
    return pacsv.WriteOptions(quoting_style="none")


def write_csv(path: str | Path, columns: Mapping[str, Any]) -> Path:
    """Writes the columns (equal-length arrays; text columns as pyarrow strings) as CSV."""
    import pyarrow.csv as pacsv

    pacsv.write_csv(_table(columns), str(path), _options())
    return Path(path)


def _as_text(values: Any) -> Any:
    """A float64 column as the text pyarrow's CSV writer would write for it (the writer's
    own conversion), each run of equal values formatted once (equal bit for bit: -0.0
    and 0.0 are two runs); any other column as it is."""
    import numpy as np

    if not (isinstance(values, np.ndarray) and values.dtype == np.float64
            and values.ndim == 1):
        return values
    import pyarrow as pa
    import pyarrow.compute as pc

    bits = values.view(np.int64)
    new = np.empty(len(values), dtype=bool)  # a run starts here
    new[:1] = True
    np.not_equal(bits[1:], bits[:-1], out=new[1:])
    starts = np.flatnonzero(new)
    if 2 * len(starts) > len(values):  # mostly changing: taking the runs' text back costs more
        return pc.cast(as_arrow(values), pa.string())
    text = pc.cast(as_arrow(values[starts]), pa.string())
    return text.take(as_arrow(np.cumsum(new, dtype=np.int64) - 1))


def as_arrow(values: Any) -> Any:
    """A float64 or int64 numpy array as a pyarrow array on its memory (pyarrow.array
    would load pandas to ask whether it is one of its types: 50 MB and a third of a
    second)."""
    import numpy as np
    import pyarrow as pa

    values = np.ascontiguousarray(values)
    kind = {np.dtype(np.float64): pa.float64(), np.dtype(np.int64): pa.int64()}[values.dtype]
    return pa.Array.from_buffers(kind, len(values), [None, pa.py_buffer(values)])


class CsvStream:
    """A CSV file written block by block (the columns of every block alike); a name
    ending in .parquet writes Parquet instead (4x faster to write than CSV: long logs)."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self._writer: Any = None  # a pyarrow Parquet or CSV writer once the first block came

    def write(self, columns: Mapping[str, Any]) -> None:
        import pyarrow.csv as pacsv

        parquet = self.path.suffix == ".parquet"
        table = _table(columns if parquet else {k: _as_text(v) for k, v in columns.items()})
        if self._writer is None:
            if parquet:
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
