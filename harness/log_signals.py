"""A machine's log as identification reads it: time, positions and inputs on even steps.

The one reader of the robots' and the model files' logs. CSV and Parquet files
(:mod:`harness.log_columns`) and MATLAB files (``scipy.io.loadmat``, one vector per
variable) are read, told by their extension. The time comes from a column, brought to
seconds by a factor, or from a stated sample rate (no time column read: the samples are
evenly spaced from t = 0). A jittering clock is resampled onto even steps and a gap refused
(:mod:`harness.clock`). Every problem raises :class:`LogSignalsError`, whose message starts
with the file's path and names the column and the line or sample.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .clock import ClockError, even_steps
from .log_columns import (
    Header,
    LogColumnError,
    check_distinct_columns,
    column_of,
    log_format,
    mean_step,
    note_slow_step,
    read_columns,
    read_header,
)
from .mat_file import MatFileError, load_mat

#: The formats read beyond CSV and Parquet, by extension.
OTHER_FORMATS = {".mat": "MATLAB"}
#: A sampling step may differ from the mean step by this fraction; a clock that jitters
#: more is resampled onto even steps, a gap refused (harness.clock).
STEP_TOLERANCE = 0.01
#: Fewer samples than this cannot identify anything.
FEWEST_SAMPLES = 10


class LogSignalsError(ValueError):
    """A log that cannot be used; the command line maps it to exit status 2."""


@dataclass(frozen=True)
class Column:
    """A signal to read: its ``role`` in messages (``q1``, a model's coordinate) and the
    file's column that holds it (a name, a 1-based column number, a MATLAB variable)."""

    role: str
    column: str


@dataclass(frozen=True)
class Signals:
    """The samples of one log, on even steps."""

    source: str
    t: np.ndarray        # (N,) [s]
    q: np.ndarray        # (N, positions)
    inputs: np.ndarray   # (N, inputs)
    resampled: str | None = None  # what was done to a jittering clock (None: nothing)

    @property
    def step(self) -> float:
        """The sampling step [s]: the mean step (robust to the rounding of epoch stamps)."""
        return float((self.t[-1] - self.t[0]) / (len(self.t) - 1))

    @property
    def samples(self) -> int:
        return int(self.t.shape[0])


def file_format(path: Path) -> str:
    """"csv", "parquet" or "MATLAB" by the extension; LogSignalsError for any other."""
    try:
        return log_format(path, OTHER_FORMATS)
    except LogColumnError as error:
        raise LogSignalsError(str(error)) from None


def header_of(path: Path) -> Header | None:
    """The column names of a CSV or Parquet log (None for a MATLAB file)."""
    if file_format(path) == "MATLAB":
        return None
    try:
        return read_header(path)
    except LogColumnError as error:
        raise LogSignalsError(str(error)) from None


def read_signals(path: str | Path, time: Column | None, positions: list[Column],
                 inputs: list[Column], *, sample_rate: float | None = None,
                 time_factor: float = 1.0, factors: np.ndarray | None = None,
                 missing_hint: str = "", slow_step_hint: str | None = None,
                 tolerance: float = STEP_TOLERANCE) -> Signals:
    """The ``time`` (None: ``sample_rate`` [Hz] gives it), ``positions`` and ``inputs``
    columns of ``path``. ``time_factor`` brings the time to seconds; ``factors`` (one per
    position and input) scales the others. ``missing_hint`` ends the message of a missing
    column; ``slow_step_hint`` (None: no check) says how to give the time's unit when the
    samples are SLOW_STEP or more apart (harness.log_columns.note_slow_step)."""
    path = Path(path)
    if (time is None) == (sample_rate is None):
        raise ValueError("give a time column or a sample rate, one of the two")
    wanted = ([] if time is None else [time]) + positions + inputs
    if file_format(path) == "MATLAB":
        data, place = _read_mat(path, wanted, missing_hint), _sample
    else:
        header = header_of(path)
        assert header is not None
        data, place = _read_table(path, header, wanted, missing_hint), header.place
    bad = ~np.isfinite(data)
    if bad.any():
        row = int(np.argmax(bad.any(axis=1)))
        which = [f"{c.role} (column {c.column!r})" if c.role != c.column else c.role
                 for c, b in zip(wanted, bad[row]) if b]
        raise LogSignalsError(f"{path} {place(row)}: {', '.join(which)} is NaN, infinite or "
                              f"missing ({int(bad.sum())} such value(s) in the log)")
    if len(data) < FEWEST_SAMPLES:
        what = ("the log has no samples (0 samples: a header row only, or nothing)"
                if len(data) == 0 else f"{len(data)} samples")
        raise LogSignalsError(f"{path}: {what}; identification needs many more")
    if time is None:
        assert sample_rate is not None
        t = np.arange(len(data)) / sample_rate
    else:
        t, data = data[:, 0] * time_factor, data[:, 1:]
    if factors is not None:  # a factor of 1 leaves the numbers as they are
        data = data * factors
    if time is not None and slow_step_hint is not None:
        note_slow_step(path, mean_step(t), slow_step_hint)
    n = len(positions)
    try:
        even = even_steps(t, data[:, :n], data[:, n:], tolerance, place,
                          "t" if time is None else time.role)
    except ClockError as error:
        raise LogSignalsError(f"{path} {error}") from None
    return Signals(str(path), even.t, even.q, even.u, even.resampled)


def _sample(index: int) -> str:
    return f"at sample {index + 1}"


def _missing(path: Path, column: Column, found: str, hint: str) -> LogSignalsError:
    return LogSignalsError(f"{path}: no column {column.column!r} for {column.role} (found: "
                           f"{found}){hint}")


def _read_table(path: Path, header: Header, wanted: list[Column], hint: str) -> np.ndarray:
    """The columns of a CSV or Parquet log, (N, len(wanted))."""
    names = []
    for column in wanted:
        name = column_of(header, column.column)  # a name or a column number
        if name is None:
            found = (", ".join(header) if header.present
                     else f"{len(header)} unnamed columns")
            raise _missing(path, column, found, hint)
        names.append(str(name))
    try:
        check_distinct_columns(str(path), header, [(c.role, header.index(name))
                                                   for c, name in zip(wanted, names)])
        return read_columns(path, header, names, [c.role for c in wanted])
    except LogColumnError as error:
        raise LogSignalsError(str(error)) from None


def _read_mat(path: Path, wanted: list[Column], hint: str) -> np.ndarray:
    """The variables of a MATLAB (v4 to v7) file, (N, len(wanted))."""
    try:
        data = load_mat(path)
    except MatFileError as error:
        raise LogSignalsError(str(error)) from None
    variables = list(dict.fromkeys(c.column for c in wanted))  # each name once: no header
    try:
        check_distinct_columns(str(path), variables,
                               [(c.role, variables.index(c.column)) for c in wanted])
    except LogColumnError as error:
        raise LogSignalsError(str(error)) from None
    available = ", ".join(sorted([*data, *data.others])) or "nothing"
    columns = []
    for column in wanted:
        if column.column in data.others:
            raise LogSignalsError(f"{path}: variable {column.column!r} ({column.role}) is not "
                                  f"a numeric vector ({data.others[column.column]})")
        if column.column not in data:
            raise _missing(path, column, available, hint)
        value = data[column.column]
        if value.ndim > 2 or min(value.shape, default=0) > 1:
            raise LogSignalsError(f"{path}: variable {column.column!r} ({column.role}) is not "
                                  f"a numeric vector (shape {value.shape}, type {value.dtype})")
        columns.append(value.astype(float).ravel())
    lengths = {len(v) for v in columns}
    if len(lengths) > 1:
        sizes = ", ".join(f"{c.column} {len(v)}" for c, v in zip(wanted, columns))
        raise LogSignalsError(f"{path}: the variables have different lengths ({sizes})")
    return np.column_stack(columns) if columns else np.empty((0, 0))
