"""The torque regression from positions and causal velocity estimates, without q''.

With the generalized momentum p = M(q) q' the dynamics read

    u = d/dt (M(q) q') - M'(q, q') q' + C(q, q') q' + G(q) + friction(q'),

every term linear in the parameters and a function of (q, q') only.  A causal filter L
applied to both sides keeps the equation exact: L u = s L[Y_M] pi - L[Y_D] pi + L[Y_R] pi,
with the regressors Y_M (of M q'), Y_D (of M' q') and Y_R (of C q' + G + friction).  No
acceleration is estimated, and no nonlinear term is evaluated at filtered signals (the
pipeline's earlier form Y(Lq, Lq', s L q') pi = L u was off by O(tau^2): the UR5's
viscous friction 0.66 % off on exact data at tau = 5 ms, 3.0 % at 10 ms).

L is two first-order stages of time constant tau; s L[Y_M] is the difference of two
samples over h, a value between them, so every other term is taken there (the mean of
the two samples).  The regressors come from the C core (RigidBody.regressor), in chunks
so that memory does not grow with the log.
"""
from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

from .layout import ParameterLayout

CHUNK = 4096      # samples per batch of regressors
EPSILON = 1e-6    # [s] of the central difference along q' that gives M'(q, q') q'


def first_order(tau: float, h: float) -> tuple[list[float], list[float]]:
    """lfilter's (b, a) of one first-order stage of time constant tau, sampled every h."""
    gain = -np.expm1(-h / tau)
    return [gain], [1.0, gain - 1.0]


def low_pass(x: np.ndarray, h: float, tau: float, stages: int = 2) -> np.ndarray:
    """x (N, ...) through `stages` first-order stages of time constant tau, at rest at
    x[0] (no start transient)."""
    b, a = first_order(tau, h)
    for _ in range(stages):
        x = lfilter(b, a, x - x[0], axis=0) + x[0]
    return x


def filtered_regression(body, q: np.ndarray, velocity: np.ndarray, u: np.ndarray, h: float,
                        tau: float, used: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(Y, z) at the samples `used` (increasing): Y (len(used), n, 12 n) and the
    filtered torques z (len(used), n) with z = Y pi, from positions q, velocity estimates
    and torques u (N, n) sampled every h.  The filter starts at rest at the first sample."""
    count, n = q.shape
    b, a = first_order(tau, h)
    # the state of each filter stage: (momentum, the rest) regressors and the torque
    states = None
    previous = None  # the last filtered sample of the chunk before: (momentum, rest, torque)
    want = np.zeros(count, dtype=bool)
    want[used] = True
    Y_out, z_out = [], []
    zeros = np.zeros((1, n))
    for start in range(0, count, CHUNK):
        stop = min(count, start + CHUNK)
        qc, vc = q[start:stop], velocity[start:stop]
        none = np.zeros_like(vc)
        gravity = body.regressor(qc, none, none)
        momentum = body.regressor(qc, none, vc) - gravity                  # M q'
        ahead, behind = qc + EPSILON * vc, qc - EPSILON * vc
        change = (body.regressor(ahead, none, vc) - body.regressor(ahead, none, none)
                  - body.regressor(behind, none, vc) + body.regressor(behind, none, none)
                  ) / (2 * EPSILON)                                        # M' q'
        rest = body.regressor(qc, vc, none) - change                       # C q' + G + F - M' q'
        signals = [momentum.reshape(len(qc), -1), rest.reshape(len(qc), -1), u[start:stop]]
        if states is None:  # at rest at the first sample's values
            states = [[lfilter_zi_at(b, a, s[0]) for _ in range(2)] for s in signals]
        filtered = []
        for k, s in enumerate(signals):
            x = s
            for stage in range(2):
                x, states[k][stage] = lfilter(b, a, x, axis=0, zi=states[k][stage])
            filtered.append(x)
        if previous is None:
            previous = [f[:1] for f in filtered]
        extended = [np.concatenate([p, f]) for p, f in zip(previous, filtered)]
        rows = np.flatnonzero(want[start:stop])  # sample 0: the filter at rest, s L = 0
        if len(rows):
            m, r, t = extended  # index j + 1 is sample start + j
            dm = (m[rows + 1] - m[rows]) / h
            Y_out.append((dm + 0.5 * (r[rows + 1] + r[rows])).reshape(len(rows), n, -1))
            z_out.append(0.5 * (t[rows + 1] + t[rows]))
        previous = [f[-1:] for f in filtered]
    if not Y_out:
        return np.zeros((0, n, ParameterLayout(n).standard_size)), zeros[:0]
    return np.concatenate(Y_out), np.concatenate(z_out)


def lfilter_zi_at(b, a, value: np.ndarray) -> np.ndarray:
    """The state of one first-order stage at rest at `value` (per column)."""
    return ((1.0 - b[0]) * np.asarray(value, float))[None, :]
