"""Numeric columns of a CSV log with a header row, as every log reader of the harness
takes them (the robots' and the model files'): read in chunks by pandas' C parser into
one array sized by the file's line count, so that a long log takes little more than its
numbers' memory; a problem raises
:class:`CsvColumnError` naming the file, and the line where there is one."""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

CHUNK_ROWS = 1 << 17


class CsvColumnError(ValueError):
    """A CSV log that cannot be read as numbers; the message names the file and line."""


class Header(list):
    """The column names of a log file; for a CSV file without a header row (its first row
    all numbers) the column numbers "1", "2", ... and `present` False.  `format` is the
    file's ("csv", or "parquet" from harness.log_columns)."""

    present: bool = True
    format: str = "csv"

    def place(self, index: int) -> str:
        """Where the data row `index` (0: the first) is in the file, for messages: its
        line in a CSV file, its row in a Parquet file."""
        if self.format == "csv":
            return f"line {index + (2 if self.present else 1)}"
        return f"row {index + 1}"


def read_header(path: Path) -> Header:
    """The column names of the first row (a UTF-8 byte-order mark allowed), or the
    column numbers of a file whose first row is already data."""
    try:
        with path.open(newline="", encoding="utf-8-sig") as handle:
            first = [name.strip() for name in next(csv.reader(handle), [])]
    except OSError as error:
        raise CsvColumnError(f"{path}: cannot open ({error.strerror or error})") from None
    except (UnicodeDecodeError, csv.Error) as error:
        raise CsvColumnError(f"{path}: not a readable UTF-8 CSV file ({error})") from None
    if not first:
        raise CsvColumnError(f"{path}: empty file")
    if all(_is_number(field) for field in first):
        header = Header(str(k + 1) for k in range(len(first)))
        header.present = False
        return header
    return Header(first)


def column_of(header: Header, column: str) -> str | None:
    """The header's name for `column`: a name, or a column number (1 = the first column)
    where no column has that name; None if there is neither."""
    if column in header:
        return column
    if column.isdigit() and 1 <= int(column) <= len(header):
        return header[int(column) - 1]
    return None


def _is_number(text: str) -> bool:
    """Whether the reader (pandas) reads `text` as a number: Python's float() also takes
    digits grouped by "_", which it refuses."""
    try:
        float(text)
    except ValueError:
        return False
    return "_" not in text


def read_columns(path: Path, header: Header, columns: list[str],
                 roles: list[str]) -> np.ndarray:
    """The named columns as floats, (N, len(columns)); `roles` names each in messages.
    A value that is not a number is named with its line; NaN, infinite or empty values
    are left as NaN for the caller to judge; a file of its header row only has no rows
    (the caller says how many samples it needs, as for any short log)."""
    import pandas as pd

    indices = [header.index(column) for column in columns]
    order = np.argsort(indices)  # pandas returns the used columns in file order
    # one array for every row (at most one a line), filled chunk by chunk: no copies
    data = np.empty((_line_count(path) + 1, len(indices)))
    rows = 0
    try:
        reader = pd.read_csv(path, header=None, skiprows=1 if header.present else 0,
                             usecols=indices, dtype=float, engine="c", chunksize=CHUNK_ROWS)
        for chunk in reader:
            if rows + len(chunk) > len(data):  # lines that end in a lone carriage return
                data = np.concatenate([data[:rows], np.empty((rows + 2 * len(chunk),
                                                              len(indices)))])
            data[rows:rows + len(chunk), order] = chunk.to_numpy()
            rows += len(chunk)
    except pd.errors.EmptyDataError:  # a header row only (or blank lines after it):
        return np.empty((0, len(indices)))  # no samples, said as for any empty log
    except (ValueError, pd.errors.ParserError) as error:
        line, role = _first_bad_value(path, indices, roles, header.present)
        said = str(error)  # the parser's words quote the value, which may be any length
        said = said if len(said) <= 200 else said[:200] + "..."
        raise CsvColumnError(f"{path} line {line}: {role} is not a number ({said})") from None
    return data[:rows] if rows > 0.9 * len(data) else data[:rows].copy()


def _line_count(path: Path, block: int = 1 << 20) -> int:
    """The number of line feeds in the file (the rows of a CSV file, but the last)."""
    count = 0
    with path.open("rb") as handle:
        while chunk := handle.read(block):
            count += chunk.count(b"\n")
    return count


def uneven_step(t: np.ndarray, tolerance: float, role: str = "t") -> tuple[int, str] | None:
    """Why the time stamps `t` are not a log's even steps: (the index of the sample after
    the first bad step, what is wrong), or None when every step is positive and within
    `tolerance` of the mean step (a logger's jitter, float64's rounding of epoch stamps)."""
    steps = np.diff(t)
    if not np.all(steps > 0):
        k = int(np.argmax(~(steps > 0)))
        return k + 1, f"{role} does not increase ({t[k]:.17g}, then {t[k + 1]:.17g})"
    mean = (t[-1] - t[0]) / (len(t) - 1)
    worst = int(np.argmax(np.abs(steps - mean)))
    if abs(steps[worst] - mean) > tolerance * mean:
        return worst + 1, (f"a step of {steps[worst]:.6g} s where the mean step is {mean:.6g} "
                           f"s; the samples must be evenly spaced within {100 * tolerance:g} % "
                           "(a gap, or a clock that jitters more: resample the log first)")
    return None


def _first_bad_value(path: Path, indices: list[int], roles: list[str],
                     has_header: bool) -> tuple[int, str]:
    """(line, what) of the first value that is not a number as the reader parses one (only
    when reading failed; line 0 when none is found)."""
    with path.open(newline="", encoding="utf-8-sig", errors="replace") as handle:
        rows = csv.reader(handle)
        first = 2 if has_header else 1
        line = first - 1  # the last line read
        try:
            if has_header:
                next(rows, None)
            for line, row in enumerate(rows, start=first):
                for index, role in zip(indices, roles):
                    text = row[index].strip() if index < len(row) else ""
                    if text and not _is_number(text):  # empty: read as NaN, judged later
                        return line, role
        except csv.Error:  # a field longer than the csv module's limit
            return line + 1, f"a field longer than {csv.field_size_limit()} characters"
    return 0, "a value"
