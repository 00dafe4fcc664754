"""The numeric columns of a log file, whatever its format: the one reader of the robots'
and the model files' logs.  The format is told by the file's extension: CSV (.csv,
.txt; read by harness.csv_columns) or Parquet (.parquet, .pq; read here by pyarrow, in
row batches, so that a long log takes little more than its numbers' memory); any other
extension is refused with a message naming the file and the formats read.  Both give
a :class:`~harness.csv_columns.Header` (the column names) and then the chosen columns
as floats; a problem raises :class:`LogColumnError` naming the file.  A log is read from
a regular file only: a device, a FIFO or a folder (also through a link) is refused by its
mode before it is opened, and a CSV file's header row must end within MAX_HEADER_BYTES
(read with that cap), so that no log makes a reader wait or read without end."""
from __future__ import annotations

import os
import stat
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np

from . import csv_columns
from .csv_columns import CHUNK_ROWS, Header, column_of, uneven_step

__all__ = ["FORMATS", "MAX_HEADER_BYTES", "Header", "LogColumnError", "check_column_roles",
           "check_distinct_columns", "check_log_file", "column_of", "log_format", "mean_step",
           "note_slow_step",
           "read_columns", "read_header", "uneven_step"]

#: The log formats read, by extension.
FORMATS = {".csv": "csv", ".txt": "csv", ".parquet": "parquet", ".pq": "parquet"}
_NAMES = {"csv": "CSV", "parquet": "Parquet"}

#: The error of every log reader (a CSV file's names its line).
LogColumnError = csv_columns.CsvColumnError

#: A CSV log's header row ends within this many bytes (thousands of column names are far
#: less); a file whose first line runs on is refused after reading this much of it.
MAX_HEADER_BYTES = 1 << 20

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


def check_distinct_columns(where: str, header: list[str], chosen: list[tuple[str, int]],
                           key: Callable[[str], str] = str) -> None:
    """LogColumnError when a role's column (``chosen``: role, index into ``header``) has a
    name the header gives more than once (which is meant cannot be told) or two roles
    read one column (one signal would be taken for two); names compared by ``key``.
    ``where`` starts the message (the file, and its line for a CSV header)."""
    names = [key(name) for name in header]
    first: dict[int, str] = {}
    for role, index in chosen:
        if names.count(names[index]) > 1:
            columns = ", ".join(str(i + 1) for i, n in enumerate(names) if n == names[index])
            raise LogColumnError(f"{where}: the header names {header[index]!r} ({role}) more "
                                 f"than once (columns {columns}); rename all but one")
        if index in first:
            raise LogColumnError(f"{where}: {first[index]} and {role} are both read from the "
                                 f"column {header[index]!r}; each needs its own column")
        first[index] = role


def check_column_roles(text: str, option: str = "--columns", fold_case: bool = False) -> None:
    """LogColumnError when the ROLE=COLUMN items of `text` (comma-separated; items without
    a role and a column are left to the caller's parser) give a role twice (the last one
    would win silently: a typo in the first goes unnoticed) or map two roles to one column
    (one signal read as two; names compared without case with `fold_case`, as the t, y, u
    reader looks them up)."""
    roles: dict[str, str] = {}
    columns: dict[str, str] = {}
    for item in filter(None, (part.strip() for part in text.split(","))):
        role, _, column = (part.strip() for part in item.partition("="))
        if not role or not column:
            continue
        if role in roles:
            raise LogColumnError(f"{option} gives {role} twice ({role}={roles[role]}, "
                                 f"{role}={column}); give each role once")
        key = column.casefold() if fold_case else column
        if key in columns:
            raise LogColumnError(f"{option} maps {columns[key]} and {role} to the same column "
                                 f"{column!r}; each role needs its own column")
        roles[role], columns[key] = column, role


def supported(others: Mapping[str, str] | None = None) -> str:
    """The formats read, for messages: "CSV (.csv, .txt), Parquet (.parquet, .pq)"."""
    kinds: dict[str, list[str]] = {}
    for suffix, kind in {**FORMATS, **(others or {})}.items():
        kinds.setdefault(_NAMES.get(kind, kind), []).append(suffix)
    return ", ".join(f"{name} ({', '.join(suffixes)})" for name, suffixes in kinds.items())


def log_format(path: Path, others: Mapping[str, str] | None = None) -> str:
    """The format of the log at `path` by its extension ("csv", "parquet", or one of
    `others`: {".mat": "MATLAB"} where a reader takes more); LogColumnError for any
    other extension, naming the file and the formats read, and for a path that is not
    a regular file or a CSV file whose header row runs on (check_log_file): every log
    reader asks this first."""
    suffix = path.suffix.lower()
    known = {**FORMATS, **(others or {})}
    if suffix not in known:
        what = f"a {suffix} file" if suffix else "a file without an extension"
        raise LogColumnError(f"{path}: {what}; logs are read as {supported(others)}: "
                             "convert it, or rename it if it is one of these")
    check_log_file(path, csv=known[suffix] == "csv")
    return known[suffix]


def _not_regular(mode: int) -> str | None:
    """What a file of this mode is when it is not a regular file ("a folder", "a
    character device" ...); None for a regular file."""
    kinds = ((stat.S_ISREG, None), (stat.S_ISDIR, "a folder"),
             (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
             (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISSOCK, "a socket"))
    return next((kind for test, kind in kinds if test(mode)), "a special file")


def check_log_file(path: Path, csv: bool = False) -> None:
    """LogColumnError naming the file when `path` (a link followed) is not a regular
    file: a device such as /dev/zero has no end, a FIFO may never give one, and neither
    can be read twice, as the readers do.  With `csv`, also when its first line (the
    header row) does not end within MAX_HEADER_BYTES.  A path where nothing is (or that
    cannot be looked at) is left to the reader, which says so."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return
    kind = _not_regular(mode)
    if kind is None and csv:
        try:
            with open(path, "rb") as handle:  # a node swapped in since: looked at again
                kind = _not_regular(os.fstat(handle.fileno()).st_mode)
                head = b"" if kind else handle.read(MAX_HEADER_BYTES + 1)
        except OSError:
            return
        if len(head) > MAX_HEADER_BYTES and not any(
                end in head[:MAX_HEADER_BYTES] for end in (b"\n", b"\r")):
            raise LogColumnError(f"{path}: the first line (the header row) does not end "
                                 f"within {MAX_HEADER_BYTES} bytes; not a CSV log")
    if kind is not None:
        link = " (through a link)" if path.is_symlink() else ""
        raise LogColumnError(f"{path}: {kind}{link}, not a regular file; a log is read "
                             "from a file (copy the data into one)")


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
