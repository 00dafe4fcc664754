"""The zero-phase derivative pipeline of inverse-model least squares (the EMPS benchmark's
IDIM-LS), with settings that follow the sample rate and the measurement noise:

1. positions through a 4th-order Butterworth low-pass, forward and backward (filtfilt: no
   phase lag); the inputs through the same filter. Its cut-off is a tenth of the sample
   rate, lowered on a noisy or coarsely quantized log to twice the highest frequency
   at which the positions stand 20 dB above their noise floor (see cutoff_for);
2. velocities and accelerations by central differences of the filtered positions;
3. the regressor Y and the known side r at every sample, the ends dropped (filter and
   difference transients);
4. Y and r decimated (8th-order Chebyshev anti-aliasing, zero phase, every 10th sample);
   with friction rows (a candidate of the cross-validation), each equation with Coulomb
   terms is first zeroed near the reversals of their coordinates (friction_mask).

At 1 kHz and with a fine encoder these are the benchmark's own choices: 100 Hz,
decimation by 10.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.signal

from .friction_rows import joint_friction_rows
from .log import LogFileError, ModelLog
from .model import Model

DIFFERENTIATORS = ("central", "spectral")
#: Butterworth cut-off as a fraction of the sample rate (100 Hz at 1 kHz).
CUTOFF_FRACTION = 0.1
ORDER = 4
DECIMATION = 10
#: Samples dropped at each end, in periods of the cut-off (50 samples at 1 kHz).
BORDER_PERIODS = 5.0
#: Fewest decimated rows per unknown.
ROWS_PER_UNKNOWN = 10
#: The positions' content counts up to where their spectrum stands this factor (20 dB)
#: above the noise floor (the median power above a quarter of the sample rate) ...
SIGNAL_TO_FLOOR = 100.0
#: ... and the cut-off is this multiple of that frequency (the Butterworth's knee must not
#: cut the motion), between a 500th and a tenth of the sample rate.
CUTOFF_MARGIN = 2.0
LOWEST_CUTOFF_FRACTION = 0.002
#: Friction rows: an equation with a coordinate's Coulomb term is left out within this
#: many periods of the cut-off of the coordinate's reversals (the filtered step of
#: sign(q') is then within 1 % of the step: 14 % after half a period, 4 % after one) ...
REVERSAL_PERIODS = 1.5
#: ... and where the coordinate moves slower than this share of its RMS speed (the robot
#: path's 0.05 rad/s, relative: a model file's coordinate has any unit).
SLOW_FRACTION = 0.05
#: A log value at least this large makes the equations' products overflow (1e154 squared
#: is the largest double).
OVERFLOWING = 1e150


@dataclass(frozen=True)
class ZeroPhase:
    """The pipeline's settings for one sampling step."""

    step: float          # [s]
    cutoff: float        # [Hz]
    order: int
    decimation: int
    border: int          # samples dropped at each end before decimation
    differentiator: str = "central"   # or "spectral"
    #: leave out each equation's rows near the reversals of the coordinates in its sign()
    #: terms (:func:`friction_mask`)
    friction_rows: bool = False

    @classmethod
    def for_step(cls, step: float, cutoff: float | None = None,
                 decimation: int = DECIMATION, differentiator: str = "central",
                 friction_rows: bool = False) -> ZeroPhase:
        """The settings at sampling step ``step`` [s] with the Butterworth cut-off
        ``cutoff`` [Hz] (default: a tenth of the sample rate), the decimation and the
        differentiator: "central" (central differences of the filtered positions) or
        "spectral" (the filter's gain and the derivatives applied in the frequency
        domain, the log mirrored at its ends: exact up to the cut-off, where central
        differences lose 15 % of an acceleration at a ninth of the sample rate)."""
        if differentiator not in DIFFERENTIATORS:
            raise ValueError(f"differentiator {differentiator!r} is not one of "
                             f"{', '.join(DIFFERENTIATORS)}")
        cutoff = CUTOFF_FRACTION / step if cutoff is None else cutoff
        border = math.ceil(BORDER_PERIODS / (cutoff * step))
        return cls(step, cutoff, ORDER, decimation, border, differentiator, friction_rows)

    @classmethod
    def for_log(cls, log: ModelLog) -> ZeroPhase:
        """The settings for a log: its step, and the cut-off its noise allows
        (:func:`cutoff_for`)."""
        return cls.for_step(log.step, cutoff_for(log))

    def as_dict(self) -> dict[str, float | int | str]:
        return {"step_s": self.step, "cutoff_hz": self.cutoff, "butterworth_order": self.order,
                "decimation": self.decimation, "border_samples": self.border,
                "differentiator": self.differentiator, "friction_rows": self.friction_rows}

    def gain(self, frequency: np.ndarray) -> np.ndarray:
        """The forward-backward Butterworth's gain at ``frequency`` [Hz] (|H|^2 of the
        bilinear design, what filtfilt applies)."""
        ratio = (np.tan(np.pi * np.minimum(frequency * self.step, 0.5 - 1e-12))
                 / math.tan(math.pi * self.cutoff * self.step))
        return 1.0 / (1.0 + ratio ** (2 * self.order))

    def low_pass(self, x: np.ndarray) -> np.ndarray:
        """``x`` (samples, ...) through the Butterworth filter, forward and backward."""
        b, a = scipy.signal.butter(self.order, 2.0 * self.cutoff * self.step)
        return scipy.signal.filtfilt(b, a, x, axis=0)


def cutoff_for(log: ModelLog) -> float:
    """The Butterworth cut-off [Hz] for a log: a tenth of the sample rate, unless some
    coordinate's position spectrum (Welch) falls to within SIGNAL_TO_FLOOR of its noise
    floor below that; then CUTOFF_MARGIN times the highest frequency where it stands
    above, at least LOWEST_CUTOFF_FRACTION of the sample rate. A fine encoder keeps the
    benchmark's tenth (EMPS: its content reaches 100 Hz); a 12-bit encoder on a slow
    pendulum gets a few hertz, where central differences of quantization steps would
    otherwise swamp the accelerations."""
    rate = 1.0 / log.step
    highest, lowest = CUTOFF_FRACTION * rate, LOWEST_CUTOFF_FRACTION * rate
    cutoff = highest
    for i in range(log.q.shape[1]):
        q = log.q[:, i]
        if not np.ptp(q) > 0.0:
            continue  # a coordinate at rest says nothing about the noise
        f, power = scipy.signal.welch(q, fs=rate, nperseg=min(4096, max(16, len(q) // 4)),
                                      detrend="linear")
        floor = float(np.median(power[f >= rate / 4]))
        above = np.flatnonzero(power > SIGNAL_TO_FLOOR * floor)
        if floor > 0.0 and len(above):
            cutoff = min(cutoff, max(CUTOFF_MARGIN * float(f[above[-1]]), lowest))
    return cutoff


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
    if settings.differentiator == "spectral":
        return _spectral(log, settings)
    q = settings.low_pass(log.q)
    qd = _above_rounding(np.gradient(q, settings.step, axis=0), q, settings.step)
    qdd = _above_rounding(np.gradient(qd, settings.step, axis=0), q, settings.step ** 2)
    inputs = settings.low_pass(log.inputs) if log.inputs.shape[1] else log.inputs
    return Derivatives(q, qd, qdd, inputs)


def spectral(x: np.ndarray, step: float, power: int,
             gain: Callable[[np.ndarray], np.ndarray] | None = None) -> np.ndarray:
    """The ``power``-th derivative of ``x`` (samples, ...) times ``gain`` (of the frequency
    [Hz]; None: 1) as products in the frequency domain, over ``x`` and its mirror image
    (so that its ends join and nothing wraps around)."""
    count = x.shape[0]
    extended = np.concatenate([x, x[::-1]], axis=0)
    frequency = np.fft.rfftfreq(extended.shape[0], step)
    factor = (2j * np.pi * frequency) ** power
    if gain is not None:
        factor = factor * gain(frequency)
    if extended.shape[0] % 2 == 0 and power % 2:
        factor[-1] = 0.0  # an odd derivative of the Nyquist bin is not real
    shape = (-1,) + (1,) * (x.ndim - 1)
    out = np.fft.irfft(np.fft.rfft(extended, axis=0) * factor.reshape(shape),
                       extended.shape[0], axis=0)
    return out[:count]


def _spectral(log: ModelLog, settings: ZeroPhase) -> Derivatives:
    """Steps 1 and 2 with the filter's gain and the derivatives in the frequency domain."""
    q = spectral(log.q, settings.step, 0, settings.gain)
    qd = _above_rounding(spectral(log.q, settings.step, 1, settings.gain), q, settings.step)
    qdd = _above_rounding(spectral(log.q, settings.step, 2, settings.gain), q,
                          settings.step ** 2)
    inputs = (spectral(log.inputs, settings.step, 0, settings.gain) if log.inputs.shape[1]
              else log.inputs)
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
    #: (rows, equations) the equations used (None: all): the rows left out are zero in
    #: Y and r; pass it to the fit so that each equation's residual counts its own rows
    mask: np.ndarray | None = None


def minimum_samples(settings: ZeroPhase, unknowns: int) -> int:
    """The shortest log the pipeline takes for a model of ``unknowns`` unknowns."""
    return 2 * settings.border + settings.decimation * ROWS_PER_UNKNOWN * max(unknowns, 3)


def check_length(model: Model, log: ModelLog, settings: ZeroPhase) -> None:
    """LogFileError for a log too short for the pipeline ``settings``."""
    needed = minimum_samples(settings, len(model.parameters))
    if log.samples < needed:
        raise LogFileError(
            f"{log.source}: {log.samples} samples ({log.samples * settings.step:g} s) is too "
            f"short: the zero-phase pipeline drops {settings.border} samples at each end and "
            f"decimates by {settings.decimation}, and {len(model.parameters)} unknowns need at "
            f"least {needed} samples")


def regression(model: Model, log: ModelLog, settings: ZeroPhase | None = None) -> Regression:
    """Steps 1-4 of the pipeline: the decimated rows of ``Y theta = r`` over the log.
    Raises LogFileError for a log too short for them."""
    settings = settings or ZeroPhase.for_log(log)
    check_length(model, log, settings)
    keep = slice(settings.border, log.samples - settings.border)
    with np.errstate(all="ignore"):  # a non-finite result is refused below, by name
        d = derivatives(log, settings)
        Y, r = model.regressor(d.q[keep], d.qd[keep], d.qdd[keep],
                               d.inputs[keep] if model.inputs else None)
    if not (np.all(np.isfinite(Y)) and np.all(np.isfinite(r))):
        raise LogFileError(f"{log.source}: the model's equations are not finite on this log "
                           f"({_why_not_finite(model, log)})")
    mask = friction_mask(model, d.qd[keep], settings) if settings.friction_rows else None
    if mask is not None:
        # zeroed before the decimation's filter: a decimated row is then a combination of
        # kept equations only, exact as they are
        Y, r = Y * mask[:, :, None], r * mask
        mask = mask[::settings.decimation].copy()
    return Regression(log.t[keep][::settings.decimation].copy(), decimate(Y, settings),
                      decimate(r, settings), settings, mask)


def _why_not_finite(model: Model, log: ModelLog) -> str:
    """The likely cause of non-finite equations on a log: values so large that the
    equations overflow (naming the column), else the model's own functions."""
    names = [*model.coordinates, *model.inputs]
    values = np.concatenate([log.q, log.inputs], axis=1)
    largest = np.max(np.abs(values), axis=0) if values.size else np.zeros(0)
    huge = [(n, v) for n, v in zip(names, largest) if not v < OVERFLOWING]
    if huge:
        return ("their terms overflow: " + ", ".join(
            f"{model.column(n)!r} ({n}) reaches {v:.3g}" for n, v in huge)
            + "; check the column's unit or scale")
    return "a division by zero or a log of a non-positive value"


def friction_mask(model: Model, qd: np.ndarray, settings: ZeroPhase) -> np.ndarray:
    """(samples, equations) True where each equation's Coulomb terms hold: every coordinate
    in its sign() terms (Model.coulomb_coordinates) is further than the filter's memory
    (REVERSAL_PERIODS of the cut-off) from a reversal of its filtered velocity ``qd``
    and faster than SLOW_FRACTION of that velocity's RMS."""
    margin = REVERSAL_PERIODS / settings.cutoff
    speed_rms = np.sqrt(np.mean(qd ** 2, axis=0))
    moving = [joint_friction_rows(qd[:, k], settings.step, margin, SLOW_FRACTION * speed_rms[k])
              for k in range(qd.shape[1])]
    mask = np.ones((len(qd), len(model.equations)), dtype=bool)
    for i, coordinates in enumerate(model.coulomb_coordinates):
        for k in coordinates:
            mask[:, i] &= moving[k]
    return mask


def decimate(x: np.ndarray, settings: ZeroPhase) -> np.ndarray:
    """Every ``decimation``-th sample of ``x`` (along axis 0) after the zero-phase
    anti-aliasing filter."""
    if settings.decimation == 1:
        return x
    return scipy.signal.decimate(x, settings.decimation, axis=0, zero_phase=True)
