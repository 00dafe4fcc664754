"""Classical, model-free estimators of velocity and acceleration from sampled positions,
and least squares for the parameters.

* Kalman filter (causal) and Rauch-Tung-Striebel smoother (offline) of the
  constant-acceleration model driven by white jerk, in steady state.
* Savitzky-Golay differentiation (offline).
* Batch least squares of an acceleration on the inverse-dynamics regressor
  [u, -sin y, -v, -sign v] (b, c1, c2, c3), also over growing windows.

The steady-state filters are linear time-invariant, so they are applied as FFT
convolutions with their (truncated) impulse responses: exact up to the
truncation (taps below 1e-17 of the first are dropped) and fast at 10 kHz.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.linalg import solve_discrete_are
from scipy.signal import fftconvolve, lfilter, savgol_coeffs, savgol_filter

# Scaled state s = [p, h v, h^2 a]: F and the white-jerk covariance no longer
# depend on h, and only lambda = q h^5 / r (q jerk spectral density, r the
# measurement variance) sets the steady-state gain.  This keeps the Riccati
# equation well scaled at any sample step.
F = np.array([[1.0, 1.0, 0.5], [0.0, 1.0, 1.0], [0.0, 0.0, 1.0]])
Q_UNIT = np.array([[1 / 20, 1 / 8, 1 / 6], [1 / 8, 1 / 3, 1 / 2], [1 / 6, 1 / 2, 1.0]])
H = np.array([[1.0, 0.0, 0.0]])


@dataclass(frozen=True)
class SteadyState:
    """Steady-state gains of the scaled model for one lambda = q h^5 / r."""

    lam: float
    A: np.ndarray  # filter: s_k = A s_{k-1} + K y_k
    K: np.ndarray
    G: np.ndarray  # RTS: s_k^s = (I - G F) s_k + G s_{k+1}^s

    @staticmethod
    def of(lam: float) -> SteadyState:
        prior = solve_discrete_are(F.T, H.T, lam * Q_UNIT, np.array([[1.0]]))
        prior = 0.5 * (prior + prior.T)
        K = prior[:, :1] / (prior[0, 0] + 1.0)
        post = (np.eye(3) - K @ H) @ prior
        G = np.linalg.solve(prior, F @ post).T  # = post F^T prior^-1 (both symmetric)
        return SteadyState(lam, (np.eye(3) - K @ H) @ F, K[:, 0], G)


def impulse_taps(A: np.ndarray, B: np.ndarray, limit: int) -> np.ndarray:
    """T_j = A^j B for j = 0.. until the taps have decayed to 1e-17 (at most limit).

    Filled by doubling (T_{m..2m-1} = A^m T_{0..m-1}), so it costs log2(n)
    matrix products instead of n Python steps."""
    rho = max(float(np.max(np.abs(np.linalg.eigvals(A)))), 1e-300)
    n = limit if rho >= 1 else min(limit, int(math.ceil(45.0 / max(-math.log(rho), 1e-12))) + 8)
    B = B.reshape(3, -1)
    T = np.empty((n, 3, B.shape[1]))
    T[0] = B
    filled, power = 1, A.copy()
    while filled < n:
        k = min(filled, n - filled)
        T[filled:filled + k] = np.einsum("ij,njm->nim", power, T[:k])
        filled += k
        power = power @ power
    return T


def _filter_scaled(y: np.ndarray, ss: SteadyState) -> np.ndarray:
    """Filtered scaled states (N, 3) of y (offset removed: the filter starts at rest)."""
    taps = impulse_taps(ss.A, ss.K, len(y))[:, :, 0]
    return fftconvolve(y[:, None], taps, axes=0)[: len(y)]


def _smooth_scaled(xf: np.ndarray, ss: SteadyState, rows: slice = slice(None)) -> np.ndarray:
    """The steady-state RTS backward pass over filtered states xf: the selected rows of
    x_k^s = sum_i G^i (I - G F) x_{k+i}, with xf extended past the end by the model's
    prediction F^m x_N, which makes the steady-state recursion start at x_N^s = x_N."""
    n = len(xf)
    taps = impulse_taps(ss.G, np.eye(3) - ss.G @ F, n)  # (ntaps, 3, 3)
    m = np.arange(1, len(taps) + 1)[:, None]
    p, v, a = xf[-1]
    tail = np.hstack([p + m * v + 0.5 * m * m * a, v + m * a, np.full_like(m, a, dtype=float)])
    z = np.vstack([xf, tail])[::-1]  # anti-causal convolution = causal on reversed data
    out = sum(fftconvolve(z[:, c:c + 1], taps[:, rows, c], axes=0)[: len(z)] for c in range(3))
    return np.asarray(out)[::-1][:n]


def _unscale(s: np.ndarray, y0: float, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scaled states back to (position, velocity, acceleration)."""
    return s[:, 0] + y0, s[:, 1] / h, s[:, 2] / h ** 2


def kalman(y: np.ndarray, h: float, lam: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Causal steady-state Kalman filter: (position, velocity, acceleration)."""
    y0 = float(y[0])
    return _unscale(_filter_scaled(y - y0, SteadyState.of(lam)), y0, h)


def rts(y: np.ndarray, h: float, lam: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Steady-state RTS smoother: (position, velocity, acceleration)."""
    y0 = float(y[0])
    ss = SteadyState.of(lam)
    return _unscale(_smooth_scaled(_filter_scaled(y - y0, ss), ss), y0, h)


def velocity_only(y: np.ndarray, h: float, lam: float, smooth: bool) -> np.ndarray:
    """The velocity alone (what the tuning loop scores): a third of the convolutions."""
    y0 = float(y[0])
    ss = SteadyState.of(lam)
    if not smooth:
        taps = impulse_taps(ss.A, ss.K, len(y))[:, 1, 0]
        return fftconvolve(y - y0, taps)[: len(y)] / h
    return _smooth_scaled(_filter_scaled(y - y0, ss), ss, slice(1, 2))[:, 0] / h


def lambda_of(q: float, h: float, r: float) -> float:
    """The dimensionless gain parameter of jerk intensity q, step h, variance r."""
    return q * h ** 5 / r


def q_of(lam: float, h: float, r: float) -> float:
    """The jerk intensity of lambda (inverse of lambda_of)."""
    return lam * r / h ** 5


def tune_log10(cost: Callable[[float], float], lo: float, hi: float, coarse: float = 1.0,
               refinements: int = 3) -> tuple[float, float]:
    """Minimize cost(10**x) over x in [lo, hi]: a grid of step ``coarse``, then halving
    steps around the best point.  Returns (best x, best cost)."""
    cache: dict[float, float] = {}

    def c(x: float) -> float:
        x = round(x, 6)
        if x not in cache:
            value = cost(10.0 ** x)
            cache[x] = value if math.isfinite(value) else math.inf
        return cache[x]

    best = min(np.arange(lo, hi + 1e-9, coarse), key=c)
    step = coarse
    for _ in range(refinements):
        step /= 2
        best = min((best - step, best, best + step), key=c)
    return float(best), c(best)


def savgol(y: np.ndarray, h: float, window: int, order: int = 3, deriv: int = 1) -> np.ndarray:
    """scipy.signal.savgol_filter(y, window, order, deriv, delta=h, mode="interp"), computed
    as an FFT convolution inside and savgol_filter on the two edges: the same numbers,
    without the O(N window) direct convolution that long windows at 10 kHz would cost."""
    if len(y) < 2 * window:
        return savgol_filter(y, window, order, deriv=deriv, delta=h, mode="interp")
    coeffs = savgol_coeffs(window, order, deriv=deriv, delta=h, use="conv")
    out = fftconvolve(y, coeffs, mode="same")
    half = window // 2
    out[:half] = savgol_filter(y[:window], window, order, deriv=deriv, delta=h,
                               mode="interp")[:half]
    out[-half:] = savgol_filter(y[-window:], window, order, deriv=deriv, delta=h,
                                mode="interp")[-half:]
    return out


def savgol_windows(rate: float, order: int = 3, longest: float = 0.6) -> list[int]:
    """Odd window lengths from order + 2 samples to ``longest`` seconds, about 19 % apart."""
    out: list[int] = []
    w = float(order + 2 if (order + 2) % 2 else order + 3)
    while w <= longest * rate:
        n = int(round(w)) | 1
        if not out or n > out[-1]:
            out.append(n)
        w *= 1.19
    return out


# ---- least squares -----------------------------------------------------------
PARAMETERS = ("b", "c1", "c2", "c3")


def regressor(u: np.ndarray, y: np.ndarray, v: np.ndarray) -> np.ndarray:
    """[u, -sin y, -v, -sign v]: acc = b u - c1 sin y - c2 v - c3 sign v."""
    return np.column_stack([u, -np.sin(y), -v, -np.sign(v)])


def least_squares(acc: np.ndarray, u: np.ndarray, y: np.ndarray, v: np.ndarray,
                  mask: np.ndarray | None = None) -> np.ndarray:
    """Batch least-squares estimate of (b, c1, c2, c3)."""
    phi = regressor(u, y, v)
    if mask is not None:
        phi, acc = phi[mask], acc[mask]
    scale = np.maximum(np.sqrt(np.mean(phi ** 2, axis=0)), 1e-300)  # equilibrate columns
    theta, *_ = np.linalg.lstsq(phi / scale, acc, rcond=None)
    return theta / scale


def growing_least_squares(t: np.ndarray, acc: np.ndarray, u: np.ndarray, y: np.ndarray,
                          v: np.ndarray, start: float, every: float
                          ) -> tuple[np.ndarray, np.ndarray]:
    """Least squares over [start, T] for T on a grid of step ``every``: (T, estimates (n, 4)).

    The normal equations are accumulated in blocks, so this costs one pass."""
    phi = regressor(u, y, v)
    first = int(np.searchsorted(t, start))
    per_block = max(1, int(round(every / float(t[1] - t[0]))))
    starts = np.arange(first, len(t), per_block)
    if len(starts) == 0:
        return np.zeros(0), np.zeros((0, 4))
    scale = np.maximum(np.sqrt(np.mean(phi[first:] ** 2, axis=0)), 1e-300)
    phi = phi[first:] / scale
    rel = starts - first
    info = np.empty((len(starts), 4, 4))
    rhs = np.empty((len(starts), 4))
    for i in range(4):
        rhs[:, i] = np.add.reduceat(phi[:, i] * acc[first:], rel)
        for j in range(i, 4):
            info[:, i, j] = info[:, j, i] = np.add.reduceat(phi[:, i] * phi[:, j], rel)
    info, rhs = np.cumsum(info, axis=0), np.cumsum(rhs, axis=0)
    ends = np.minimum(starts + per_block, len(t)) - 1
    ridge = 1e-12 * np.trace(info[-1]) * np.eye(4)  # only guards the first, short windows
    theta = np.linalg.solve(info + ridge, rhs[..., None])[..., 0] / scale
    return t[ends], theta


def windowed_damping(t: np.ndarray, xi: np.ndarray, v: np.ndarray, memory: float,
                     causal: bool) -> np.ndarray:
    """d(t) from xi = -d v by local least squares: exponential forgetting with time
    constant ``memory`` (causal, like the FMU's MFF) or the same filter run forwards and
    backwards (offline, centred)."""
    lam = math.exp(-float(t[1] - t[0]) / memory)

    def smooth(x: np.ndarray) -> np.ndarray:  # one-pole low pass started at x[0]
        return lfilter([1 - lam], [1, -lam], x, zi=[lam * x[0]])[0]

    num, den = -xi * v, v * v
    if causal:
        num_f, den_f = smooth(num), smooth(den)
    else:  # forward and backward: a symmetric two-sided exponential window, no lag
        num_f, den_f = smooth(smooth(num)[::-1])[::-1], smooth(smooth(den)[::-1])[::-1]
    return num_f / np.maximum(den_f, 1e-12)
