"""A measured log for a model file: time, positions and inputs, by the model's [columns].

Read by the one log reader (:mod:`harness.log_signals`: CSV, Parquet and MATLAB files, a
jittering clock resampled, a gap refused). The time column is in the unit of the model
file's ``[units] t`` (default s) and is brought to seconds; the other columns stay in the
file's units (the regressor scales them, harness.model.model).
"""
from __future__ import annotations

from pathlib import Path

from ..log_signals import Column, LogSignalsError, Signals, read_signals
from ..units import factor
from .model import Model
from .reader import TIME

#: A log that cannot be used for the model; the command line maps it to exit status 2.
LogFileError = LogSignalsError
#: The samples of one log, in the units of the model file.
ModelLog = Signals


def read_log(path: str | Path, model: Model, sample_rate: float | None = None) -> ModelLog:
    """The time, coordinate and input columns of ``path`` that ``model.columns`` names.
    With a sample rate [Hz] (``sample_rate``, else the model's [log] sample_rate), the
    samples are evenly spaced at it from t = 0, and no time column is read."""
    rate = sample_rate if sample_rate is not None else model.sample_rate
    hint = "; the model's [columns] maps a name to a column"
    return read_signals(
        path, None if rate is not None else Column(f"time column {model.column(TIME)!r}",
                                                    model.column(TIME)),
        [Column(c, model.column(c)) for c in model.coordinates],
        [Column(u, model.column(u)) for u in model.inputs], sample_rate=rate,
        time_factor=factor(model.time_unit or "s", "s"), missing_hint=hint,
        slow_step_hint=None if model.time_unit is not None else
        'write t = "ms" in the model file\'s [units] (t = "s" confirms seconds)')
