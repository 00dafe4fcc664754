"""A measured log for a model file: time, positions and inputs, by the model's [columns].

CSV and Parquet files (harness.log_columns, the reader of the robots' logs too) and
MATLAB files (``scipy.io.loadmat``, one vector per variable) are read, told by their
extension; every problem raises :class:`LogFileError`, whose message starts with the
file's path and names the column or line.  The time column is in the unit of the model
file's ``[units] t`` (default s) and is brought to seconds; the other columns stay in
the file's units (the regressor scales them, harness.model.model).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..clock import ClockError, even_steps
from ..log_columns import (
    LogColumnError,
    column_of,
    log_format,
    note_slow_step,
    read_columns,
    read_header,
)
from ..units import factor
from .model import Model
from .reader import TIME

#: A sampling step may differ from the mean step by this fraction; a clock that jitters
#: more is resampled onto even steps, a gap refused (harness.clock).
STEP_TOLERANCE = 0.01


class LogFileError(ValueError):
    """A log that cannot be used for the model; the command line maps it to exit status 2."""


@dataclass(frozen=True)
class ModelLog:
    """The samples of one log, in the units of the model file."""

    source: str
    t: np.ndarray        # (N,) [s]
    q: np.ndarray        # (N, coordinates)
    inputs: np.ndarray   # (N, inputs)
    resampled: str | None = None  # what was done to a jittering clock (None: nothing)

    @property
    def step(self) -> float:
        """The sampling step [s]: the mean step (the steps are checked to be even)."""
        return float((self.t[-1] - self.t[0]) / (len(self.t) - 1))

    @property
    def samples(self) -> int:
        return int(self.t.shape[0])


def read_log(path: str | Path, model: Model, sample_rate: float | None = None) -> ModelLog:
    """The time, coordinate and input columns of ``path`` that ``model.columns`` names.
    With a sample rate [Hz] (``sample_rate``, else the model's [log] sample_rate), the
    samples are evenly spaced at it from t = 0, and no time column is read."""
    path = Path(path)
    rate = sample_rate if sample_rate is not None else model.sample_rate
    names = ([] if rate is not None else [TIME]) + [*model.coordinates, *model.inputs]
    wanted = {name: model.column(name) for name in names}
    try:
        kind = log_format(path, {".mat": "MATLAB"})
    except LogColumnError as error:
        raise LogFileError(str(error)) from None
    if kind == "MATLAB":
        columns = _read_mat(path, list(wanted.values()))
    else:
        columns = _read_table(path, list(wanted.values()))
    lengths = {len(v) for v in columns.values()}
    if len(lengths) != 1:
        sizes = ", ".join(f"{k} {len(v)}" for k, v in columns.items())
        raise LogFileError(f"{path}: the columns have different lengths ({sizes})")
    for name, column in wanted.items():
        bad = np.flatnonzero(~np.isfinite(columns[column]))
        if bad.size:
            raise LogFileError(f"{path}: column {column!r} ({name}) has {bad.size} NaN or "
                               f"infinite value(s), the first at sample {bad[0] + 1}")
    if rate is not None:
        t = np.arange(len(next(iter(columns.values())))) / rate
    else:
        t = columns[wanted[TIME]] * factor(model.time_unit or "s", "s")  # [units] t: a time
    if len(t) < 3:
        raise LogFileError(f"{path}: {len(t)} samples; identification needs many more")
    if model.time_unit is None and rate is None:
        note_slow_step(path, (t[-1] - t[0]) / (len(t) - 1), 'write t = "ms" in the model '
                       'file\'s [units] (t = "s" confirms seconds)')
    q = np.column_stack([columns[wanted[c]] for c in model.coordinates])
    u = (np.column_stack([columns[wanted[u]] for u in model.inputs]) if model.inputs
         else np.empty((len(t), 0)))
    try:
        even = even_steps(t, q, u, STEP_TOLERANCE, lambda k: f"at sample {k + 1}",
                          f"time column {model.column(TIME)!r}")
    except ClockError as error:
        raise LogFileError(f"{path}: {error}") from None
    return ModelLog(str(path), even.t, even.q, even.u, even.resampled)


def _missing(path: Path, column: str, available: list[str]) -> LogFileError:
    return LogFileError(f"{path}: no column {column!r} (the model's [columns] maps a name to "
                        f"it; the log has: {', '.join(available) or 'nothing'})")


def _read_mat(path: Path, wanted: list[str]) -> dict[str, np.ndarray]:
    import scipy.io

    try:
        data = scipy.io.loadmat(str(path))
    except FileNotFoundError:
        raise LogFileError(f"{path}: no such file") from None
    except NotImplementedError:  # MATLAB v7.3 files are HDF5
        raise LogFileError(f"{path}: a MATLAB v7.3 (HDF5) file; save it with -v7 or as "
                           "CSV") from None
    except (OSError, ValueError, TypeError) as exc:
        raise LogFileError(f"{path}: not a readable MATLAB file ({exc})") from None
    available = sorted(k for k in data if not k.startswith("__"))
    out = {}
    for column in wanted:
        if column not in data:
            raise _missing(path, column, available)
        value = np.asarray(data[column])
        if value.dtype.kind not in "fiub" or value.ndim > 2 or min(value.shape, default=0) > 1:
            raise LogFileError(f"{path}: variable {column!r} is not a numeric vector (shape "
                               f"{value.shape}, type {value.dtype})")
        out[column] = value.astype(float).ravel()
    return out


def _read_table(path: Path, wanted: list[str]) -> dict[str, np.ndarray]:
    """The columns of a CSV or Parquet log."""
    try:
        header = read_header(path)
        named = [column_of(header, column) for column in wanted]  # names or column numbers
        for column, name in zip(wanted, named):
            if name is None:
                raise _missing(path, column, header)
        data = read_columns(path, header, [str(name) for name in named],
                            [f"column {c!r}" for c in wanted])
    except LogColumnError as error:
        raise LogFileError(str(error)) from None
    return {column: data[:, k].copy() for k, column in enumerate(wanted)}
