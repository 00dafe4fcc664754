"""The zero-phase derivative pipeline of inverse-model least squares (the EMPS benchmark's
IDIM-LS), with settings that follow the sample rate:

1. positions through a 4th-order Butterworth low-pass at a tenth of the sample rate,
   forward and backward (filtfilt: no phase lag); the inputs through the same filter;
2. velocities and accelerations by central differences of the filtered positions;
3. the regressor Y and the known side r at every sample, the ends dropped (filter and
   difference transients);
4. Y and r decimated (8th-order Chebyshev anti-aliasing, zero phase, every 10th sample).

At 1 kHz these are the benchmark's own choices: 100 Hz, decimation by 10.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.signal

from .log import LogFileError, ModelLog
from .model import Model

#: Butterworth cut-off as a fraction of the sample rate (100 Hz at 1 kHz).
CUTOFF_FRACTION = 0.1
ORDER = 4
DECIMATION = 10
#: Samples dropped at each end, in periods of the cut-off (50 samples at 1 kHz).
BORDER_PERIODS = 5.0
#: Fewest decimated rows per unknown.
ROWS_PER_UNKNOWN = 10


@dataclass(frozen=True)
class ZeroPhase:
    """The pipeline's settings for one sampling step."""

    step: float          # [s]
    cutoff: float        # [Hz]
    order: int
    decimation: int
    border: int          # samples dropped at each end before decimation

    @classmethod
    def for_step(cls, step: float) -> ZeroPhase:
        """The defaults at sampling step ``step`` [s]."""
        cutoff = CUTOFF_FRACTION / step
        border = math.ceil(BORDER_PERIODS / (cutoff * step))
        return cls(step, cutoff, ORDER, DECIMATION, border)

    def as_dict(self) -> dict[str, float | int]:
        return {"step_s": self.step, "cutoff_hz": self.cutoff, "butterworth_order": self.order,
                "decimation": self.decimation, "border_samples": self.border}

    def low_pass(self, x: np.ndarray) -> np.ndarray:
        """``x`` (samples, ...) through the Butterworth filter, forward and backward."""
        b, a = scipy.signal.butter(self.order, 2.0 * self.cutoff * self.step)
        return scipy.signal.filtfilt(b, a, x, axis=0)


@dataclass(frozen=True)
class Derivatives:
    """Filtered positions, their central-difference velocities and accelerations, and the
    filtered inputs, at every sample of a log (file units)."""

    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    inputs: np.ndarray


def derivatives(log: ModelLog, settings: ZeroPhase) -> Derivatives:
    """Steps 1 and 2 of the pipeline over the whole log."""
    q = settings.low_pass(log.q)
    qd = _above_rounding(np.gradient(q, settings.step, axis=0), q, settings.step)
    qdd = _above_rounding(np.gradient(qd, settings.step, axis=0), q, settings.step ** 2)
    inputs = settings.low_pass(log.inputs) if log.inputs.shape[1] else log.inputs
    return Derivatives(q, qd, qdd, inputs)


def _above_rounding(derivative: np.ndarray, q: np.ndarray, scale: float) -> np.ndarray:
    """``derivative`` with the values a position at rest gets from rounding alone set to
    0: otherwise sign(der(x)) of a coordinate that never moves is +-1 at random, a
    column that looks excited."""
    floor = 64 * np.finfo(float).eps * np.max(np.abs(q), axis=0) / scale
    return np.where(np.abs(derivative) > floor, derivative, 0.0)


@dataclass(frozen=True)
class Regression:
    """The decimated regressor rows of a log: ``Y theta = r`` (SI, theta in file units)."""

    t: np.ndarray    # (rows,) [s]
    Y: np.ndarray    # (rows, equations, unknowns)
    r: np.ndarray    # (rows, equations)
    settings: ZeroPhase


def minimum_samples(settings: ZeroPhase, unknowns: int) -> int:
    """The shortest log the pipeline takes for a model of ``unknowns`` unknowns."""
    return 2 * settings.border + settings.decimation * ROWS_PER_UNKNOWN * max(unknowns, 3)


def regression(model: Model, log: ModelLog, settings: ZeroPhase | None = None) -> Regression:
    """Steps 1-4 of the pipeline: the decimated rows of ``Y theta = r`` over the log.
    Raises LogFileError for a log too short for them."""
    settings = settings or ZeroPhase.for_step(log.step)
    needed = minimum_samples(settings, len(model.parameters))
    if log.samples < needed:
        raise LogFileError(
            f"{log.source}: {log.samples} samples ({log.samples * settings.step:g} s) is too "
            f"short: the zero-phase pipeline drops {settings.border} samples at each end and "
            f"decimates by {settings.decimation}, and {len(model.parameters)} unknowns need at "
            f"least {needed} samples")
    d = derivatives(log, settings)
    keep = slice(settings.border, log.samples - settings.border)
    Y, r = model.regressor(d.q[keep], d.qd[keep], d.qdd[keep],
                           d.inputs[keep] if model.inputs else None)
    if not (np.all(np.isfinite(Y)) and np.all(np.isfinite(r))):
        raise LogFileError(f"{log.source}: the model's equations are not finite on this log "
                           "(a division by zero or a log of a non-positive value)")
    return Regression(log.t[keep][::settings.decimation].copy(), decimate(Y, settings),
                      decimate(r, settings), settings)


def decimate(x: np.ndarray, settings: ZeroPhase) -> np.ndarray:
    """Every ``decimation``-th sample of ``x`` (along axis 0) after the zero-phase
    anti-aliasing filter."""
    return scipy.signal.decimate(x, settings.decimation, axis=0, zero_phase=True)
