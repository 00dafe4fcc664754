"""The numeric columns of a log file, whatever its format: the one reader of the robots'
and the model files' logs.  The format is told by the file's extension: CSV (.csv,
.txt; read by harness.csv_columns) or Parquet (.parquet, .pq; read here by pyarrow, in
row batches, so that a long log takes little more than its numbers' memory); any other
extension is refused with a message naming the file and the formats read.  Both give
a :class:`~harness.csv_columns.Header` (the column names) and then the chosen columns
as floats; a problem raises :class:`LogColumnError` naming the file."""
from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from . import csv_columns
from .csv_columns import CHUNK_ROWS, Header, column_of, uneven_step

__all__ = ["FORMATS", "Header", "LogColumnError", "column_of", "log_format", "mean_step",
           "note_slow_step",
           "read_columns", "read_header", "uneven_step"]

#: The log formats read, by extension.
FORMATS = {".csv": "csv", ".txt": "csv", ".parquet": "parquet", ".pq": "parquet"}
_NAMES = {"csv": "CSV", "parquet": "Parquet"}

#: The error of every log reader (a CSV file's names its line).
LogColumnError = csv_columns.CsvColumnError

#: Samples this far apart [s] or more are likely not in seconds (a robot's or a
#: machine's log is sampled at 10 Hz or faster).
SLOW_STEP = 0.5


def mean_step(t: np.ndarray) -> float:
    """The mean sample step ``(t[-1] - t[0]) / (samples - 1)`` of a time column of at
    least two samples, without an overflow on the way (times near 1e308 apart: each end
    is divided first; the difference is inf only when the step itself is beyond float64)."""
    intervals = len(t) - 1
    return float(t[-1]) / intervals - float(t[0]) / intervals  # floats: no numpy warning


def note_slow_step(path: Path, step: float, hint: str) -> None:
    """A warning (counted: the command then exits 1) when the time column, read as
    seconds without a unit being given, has samples SLOW_STEP or more apart: likely
    milliseconds.  `hint` says how to give the unit."""
    if step >= SLOW_STEP:
        from .messages import note
        note(f"{path}: samples {step:g} s apart, the time column read as seconds: if it is "
             f"in milliseconds (or us, ns), {hint}")


def supported(others: Mapping[str, str] | None = None) -> str:
    """The formats read, for messages: "CSV (.csv, .txt), Parquet (.parquet, .pq)"."""
    kinds: dict[str, list[str]] = {}
    for suffix, kind in {**FORMATS, **(others or {})}.items():
        kinds.setdefault(_NAMES.get(kind, kind), []).append(suffix)
    return ", ".join(f"{name} ({', '.join(suffixes)})" for name, suffixes in kinds.items())


def log_format(path: Path, others: Mapping[str, str] | None = None) -> str:
    """The format of the log at `path` by its extension ("csv", "parquet", or one of
    `others`: {".mat": "MATLAB"} where a reader takes more); LogColumnError for any
    other extension, naming the file and the formats read."""
    suffix = path.suffix.lower()
    known = {**FORMATS, **(others or {})}
    if suffix in known:
        return known[suffix]
    what = f"a {suffix} file" if suffix else "a file without an extension"
    raise LogColumnError(f"{path}: {what}; logs are read as {supported(others)}: convert "
                         "it, or rename it if it is one of these")


def read_header(path: Path) -> Header:
    """The column names of the log at `path` (see csv_columns.read_header for a CSV
    file without a header row)."""
    if log_format(path) == "csv":
        return csv_columns.read_header(path)
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        schema = pq.read_schema(path)
    except (FileNotFoundError, IsADirectoryError, PermissionError) as error:
        raise LogColumnError(f"{path}: cannot open ({error.strerror or error})") from None
    except (pa.ArrowException, OSError) as error:
        raise LogColumnError(f"{path}: not a readable Parquet file ({error})") from None
    header = Header(schema.names)
    header.format = "parquet"
    if not header:
        raise LogColumnError(f"{path}: a Parquet file without columns")
    return header


def read_columns(path: Path, header: Header, columns: list[str],
                 roles: list[str]) -> np.ndarray:
    """The named columns as floats, (N, len(columns)); `roles` names each in messages.
    A value that is not a number is refused naming its column (and line, in a CSV file);
    NaN, infinite, empty or null values are left as NaN for the caller to judge."""
    if header.format == "csv":
        return csv_columns.read_columns(path, header, columns, roles)
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        table = pq.ParquetFile(path)
        schema = table.schema_arrow
        for column, role in zip(columns, roles):
            kind = schema.field(column).type
            if not (pa.types.is_integer(kind) or pa.types.is_floating(kind)
                    or pa.types.is_decimal(kind)):
                raise LogColumnError(f"{path}: column {column!r} ({role}) holds {kind}, not "
                                     "numbers (the columns read must be numeric: time stamps "
                                     "too, e.g. as seconds)")
        wanted = list(dict.fromkeys(columns))
        chunks = []
        for batch in table.iter_batches(batch_size=CHUNK_ROWS, columns=wanted):
            chunks.append(np.column_stack([
                batch.column(column).cast(pa.float64()).to_numpy(zero_copy_only=False)
                for column in columns]))
    except (pa.ArrowException, OSError) as error:
        raise LogColumnError(f"{path}: not a readable Parquet file ({error})") from None
    return np.concatenate(chunks) if chunks else np.empty((0, len(columns)))
