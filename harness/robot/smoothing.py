"""Zero-phase velocities for the offline pipeline: Savitzky-Golay derivatives whose
window each joint chooses from its own data (Lepski's rule), and the regression's window
that follows from them.

A fixed 0.05 s velocity window left exact samples 9-1200 times the oracle-tuned causal
Kalman filter's velocity RMS (its polynomial cannot follow a multi-sine over 50 ms) and
was too short for 17-bit encoders at 10 kHz; per joint, growing the window while the
estimate stays within the noise of every shorter one gave 0.17-0.57 times the Kalman
filter's on the robot bench's logs (docs/robots.md).
"""
from __future__ import annotations

import numpy as np
from scipy.ndimage import convolve1d
from scipy.signal import savgol_coeffs, savgol_filter

from .joint_log import JointLog, LogError

ORDER = 4      # polynomial order of the fits
GROWTH = 1.15  # between candidate windows
KAPPA = 2.0    # a longer window is kept while it differs from each shorter one by less
#               than KAPPA times that one's noise (1 failed on 17-bit encoders at 10 kHz,
#               whose rounding is not white over 7 samples; 4 chose windows too long)
LONGEST = 0.3  # [s]
# the regression's shortest window [s]: the fixed window the parameters were validated with,
# which a fine encoder keeps (regression_window)
SHORTEST_REGRESSION_WINDOW = 0.05
CHUNK = 1 << 15  # samples compared at a time


def noise_std(x: np.ndarray) -> float:
    """The measurement noise of one joint's positions: the median absolute fourth
    difference (for white noise of std s its variance is 70 s^2; a smooth trajectory
    adds only h^4 q'''' to it, and the median ignores the kinks of a velocity reversal)."""
    fourth = np.diff(x, 4)
    return float(np.median(np.abs(fourth)) / 0.6745 / np.sqrt(70.0))


def candidate_windows(h: float, samples: int) -> list[int]:
    """Odd window lengths from ORDER + 3 samples up, GROWTH apart, at most LONGEST and a
    third of the log."""
    longest = min(LONGEST / h, samples / 3)
    windows, length = [], ORDER + 3
    while length <= longest:
        windows.append(length if length % 2 else length + 1)
        length = int(np.ceil(length * GROWTH)) + 1
    return sorted(set(windows)) or [ORDER + 3]


def joint_velocity(x: np.ndarray, h: float, chunk: int | None = None
                   ) -> tuple[np.ndarray, float]:
    """One joint's velocity and the window chosen [s].  Lepski's rule: the longest
    candidate whose velocity is within KAPPA standard deviations (of white noise of the
    estimated level) of every shorter candidate's, compared away from the log's ends.

    The comparisons run over `chunk` samples at a time (None: CHUNK) (every candidate still in the
    running over the same samples), so that memory does not grow with the number of
    candidates; a candidate whose differences already exceed the bound ends the
    candidates after it.  Only the chosen window's velocity is computed over the whole log."""
    chosen = _chosen_window(x, h, chunk or CHUNK)
    return savgol_filter(x, chosen, ORDER, deriv=1, delta=h), chosen * h


def _chosen_window(x: np.ndarray, h: float, chunk: int) -> int:
    """The window [samples] Lepski's rule keeps for one joint's positions x."""
    windows = candidate_windows(h, x.size)
    return windows[_lepski(x, h, windows, chunk)]


def _lepski(x: np.ndarray, h: float, windows: list[int], chunk: int) -> int:
    """The index of the window Lepski's rule keeps (joint_velocity): the window before
    the first whose velocity differs from a shorter one's by more than KAPPA times that
    one's noise (root mean square over the samples at least the longest window's half
    away from the ends, where every candidate is the same convolution of x)."""
    half = windows[-1] // 2
    start, stop = half + 1, x.size - half - 1
    count = max(stop - start, 0)
    sigma = max(noise_std(x), 1e-15 * (1.0 + float(np.max(np.abs(x)))))
    coefficients = [savgol_coeffs(length, ORDER, deriv=1, delta=h) for length in windows]
    # a shorter window s fails a longer one when the sum of squares exceeds this
    bound = [count * (KAPPA * sigma * float(np.sqrt(np.sum(c ** 2)))) ** 2
             for c in coefficients]
    squares = np.zeros((len(windows), len(windows)))  # [longer, shorter]
    running = len(windows)  # the windows still in the running: 0 .. running - 1
    for first in range(start, stop, chunk):
        last = min(stop, first + chunk)
        segment = x[first - half:last + half]
        velocities = [convolve1d(segment, c, mode="constant")[half:half + last - first]
                      for c in coefficients[:running]]
        for longer in range(1, running):
            for shorter in range(longer):
                squares[longer, shorter] += np.sum(
                    (velocities[longer] - velocities[shorter]) ** 2)
            if np.any(squares[longer, :longer] > bound[:longer]):
                running = longer  # it fails however the other samples compare
                break
    return running - 1


def adaptive_velocities(q: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Every joint's zero-phase velocity (N, n) and the window each chose [s] (n,)."""
    _check_length(q)
    velocity, windows = np.empty(q.shape), np.empty(q.shape[1])
    for i in range(q.shape[1]):
        velocity[:, i], windows[i] = joint_velocity(q[:, i], h)
    return velocity, windows


def velocity_windows(q: np.ndarray, h: float) -> np.ndarray:
    """The window each joint's velocity would choose [s] (n,), without the velocities."""
    _check_length(q)
    return np.array([_chosen_window(q[:, i], h, CHUNK) * h for i in range(q.shape[1])])


def _check_length(q: np.ndarray) -> None:
    if q.shape[0] < 3 * (ORDER + 3):
        raise ValueError(f"the log ({q.shape[0]} samples) is too short for the velocities")


def regression_window(velocity_windows: np.ndarray) -> float:
    """The regression's Savitzky-Golay window [s] when none is given: the longest of the
    joints' velocity windows (adaptive_velocities), at least SHORTEST_REGRESSION_WINDOW.
    One window serves every joint (the torques and every joint's accelerations must pass
    the same filter), and an acceleration needs at least the window the noisiest joint's
    velocity needs: a 0.01 rad encoder at 200 Hz gets about 0.3 s, where 0.05 s turned its
    steps into accelerations of noise; a 17-bit encoder keeps 0.05-0.14 s."""
    longest = float(np.max(velocity_windows)) if len(velocity_windows) else 0.0
    return max(SHORTEST_REGRESSION_WINDOW, longest)


def _odd(count: int) -> int:
    return count if count % 2 else count + 1


def savitzky_golay(log: JointLog, window: float, order: int = 4,
                   at: np.ndarray | None = None):
    """(q, q', q'', u) smoothed by one zero-phase Savitzky-Golay filter of `window` s,
    at the samples `at` (None: every sample); a column at a time, so that a long log
    needs one column's work space, not four arrays of the log's length."""
    rows = slice(None) if at is None else at
    out = []
    for x, deriv in ((log.q, 0), (log.q, 1), (log.q, 2), (log.u, 0)):
        smooth = np.empty((len(x) if at is None else len(at), x.shape[1]))
        for i in range(x.shape[1]):
            smooth[:, i] = smooth_column(log, x[:, i], window, order, deriv)[rows]
        out.append(smooth)
    return tuple(out)


def smooth_column(log: JointLog, x: np.ndarray, window: float, order: int = 4,
            deriv: int = 0) -> np.ndarray:
    """One column x (N,) of the log through the Savitzky-Golay filter of `window` s."""
    length = _odd(max(order + 2, round(window / log.step)))
    if length > len(log.t):
        raise LogError(f"the Savitzky-Golay window ({length} samples) is longer than the log")
    return savgol_filter(x, length, order, deriv=deriv, delta=log.step)


def observer_velocities(log: JointLog, acceleration_bound: np.ndarray) -> np.ndarray:
    """Each joint's velocity by the observer FMU's default estimator without a model
    (harness.robot.native.observe_adaptive: the implicit super-twisting observer beside
    the noise-adaptive bank of linear observers, which estimates the encoder noise
    itself): causal, the estimate at a sample from the positions up to it."""
    from .native import observe_adaptive
    return observe_adaptive(log.q, log.step, acceleration_bound).velocity
