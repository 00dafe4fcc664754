"""A log's clock as the identification needs it: even steps.

A clock whose steps stay within a tolerance of their mean is taken as it is. One that
jitters beyond it (a logger on a general-purpose computer: 94 Hz with steps from 8 to
13 ms) is resampled onto even steps of its mean step: the positions through cubic
splines (their derivatives stay smooth), the other columns linearly (a force held between
samples is not smoother than the samples). A step more than GAP_STEPS times the median,
or one that does not increase, is a gap: refused, naming where it is. The robot and
model-file readers share it.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .csv_columns import uneven_step

#: A step this many times the median step is a gap (refused); shorter uneven steps are a
#: jittering clock (the log is resampled).
GAP_STEPS = 2.5
#: The mean sample step [s] of a log a machine's motion is identified from: from 1 ns
#: (no logger samples faster) to 10^4 s (nearly three hours between samples).  Outside,
#: the derivatives, which divide by powers of the step, leave float64 (a step of 1e302 s
#: overflows), and the stamps' span must be a finite number of seconds.
STEP_RANGE = (1e-9, 1e4)


class ClockError(ValueError):
    """A clock that cannot be made even (a gap, a step that does not increase); the
    message names the sample through the reader's ``place``."""


@dataclass(frozen=True)
class EvenLog:
    """Time, positions and the other columns on even steps."""

    t: np.ndarray
    q: np.ndarray
    u: np.ndarray
    resampled: str | None = None  # what was done to a jittering clock (None: nothing)


def even_steps(t: np.ndarray, q: np.ndarray, u: np.ndarray, tolerance: float,
               place: Callable[[int], str], role: str = "t") -> EvenLog:
    """The log on even steps (see the module); ClockError names a gap's place, or the
    mean step when it is outside STEP_RANGE."""
    _check_span(t, place, role)
    uneven = uneven_step(t, tolerance, role)
    if uneven is None:
        return EvenLog(t, q, u)
    steps = np.diff(t)
    typical = float(np.median(steps))
    gap = int(np.argmax(steps)) if steps.size else 0
    if not np.all(steps > 0) or steps[gap] > GAP_STEPS * typical:
        where = uneven[0] if not np.all(steps > 0) else gap + 1
        why = uneven[1] if not np.all(steps > 0) else (
            f"a gap of {steps[gap]:.6g} s where the steps are typically {typical:.6g} s: "
            f"the log is not continuous there; cut it into continuous pieces")
        raise ClockError(f"{place(where)}: {why}")
    return _resampled(t, q, u)


def _check_span(t: np.ndarray, place: Callable[[int], str], role: str) -> None:
    """ClockError unless the stamps span a finite time whose mean step is in STEP_RANGE."""
    if len(t) < 2:
        return  # the callers say how many samples they need
    with np.errstate(over="ignore", invalid="ignore"):
        span = float(t[-1]) - float(t[0])
    if not np.isfinite(span):
        raise ClockError(f"{place(len(t) - 1)}: {role} spans {t[0]:.6g} to {t[-1]:.6g} s, "
                         f"beyond what float64 holds as a duration")
    mean = span / (len(t) - 1)
    low, high = STEP_RANGE
    if span > 0 and not low <= mean <= high:
        raise ClockError(f"{place(1)}: {role} steps by {mean:.6g} s on average; a log's "
                         f"step is from {low:g} to {high:g} s (is the time unit right?)")


def _resampled(t: np.ndarray, q: np.ndarray, u: np.ndarray) -> EvenLog:
    from scipy.interpolate import make_interp_spline

    even = np.linspace(t[0], t[-1], len(t))
    positions = make_interp_spline(t, q, k=3, axis=0)(even)
    others = np.column_stack([np.interp(even, t, u[:, i]) for i in range(u.shape[1])]) \
        if u.shape[1] else np.empty((len(t), 0))
    steps = np.diff(t)
    return EvenLog(even, positions, others,
                   f"the clock jitters (steps from {steps.min():.6g} to {steps.max():.6g} s): "
                   f"the log is resampled onto even steps of {even[1] - even[0]:.6g} s "
                   f"(positions by cubic splines, the other columns linearly)")
