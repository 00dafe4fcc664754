"""Causal velocity estimates of a model's coordinates, with their +-2 sigma bands.

The velocities come from the observer FMU's default estimator without a model
(:func:`harness.robot.native.observe_adaptive`: the implicit super-twisting observer
beside a bank of noise-adaptive linear observers, C core), one coordinate at a time: the
estimate at a sample uses the measurements up to it. The bands are approximate: the
steady-state Kalman covariance of a constant-acceleration model at the published
observer's bandwidth, scaled by the noise the bank estimates.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import scipy.linalg

from .log import ModelLog

#: The observer's acceleration bound is this factor times the largest |q''| of the
#: zero-phase pipeline (Theorem 3.1 gains need a bound, not its exact value).
BOUND_MARGIN = 1.5


@dataclass(frozen=True)
class Estimates:
    """Per sample and coordinate (samples, coordinates), in the file's units."""

    position: np.ndarray
    velocity: np.ndarray
    position_std: np.ndarray
    velocity_std: np.ndarray
    noise: np.ndarray       # the estimated measurement noise std
    bandwidth: np.ndarray   # of the published observer [rad/s]


@lru_cache(maxsize=256)
def kalman_std(omega: float, step: float) -> tuple[float, float]:
    """Position and velocity error std per unit measurement noise std of the filter
    x1+ = x1 + h v + h^2 a, v+ = v + h a, a+ = a + w with var(w) = omega^6 h^2 (the bank's
    members' model and ratio, fmu/src/core/noise_adaptive.h), after each measurement."""
    h = step
    F = np.array([[1.0, h, h * h], [0.0, 1.0, h], [0.0, 0.0, 1.0]])
    H = np.array([[1.0, 0.0, 0.0]])
    Q = np.diag([0.0, 0.0, max(omega, 1e-9) ** 6 * h * h])
    prior = scipy.linalg.solve_discrete_are(F.T, H.T, Q + 1e-30 * np.eye(3), np.eye(1))
    gain = prior @ H.T / (prior[0, 0] + 1.0)
    posterior = prior - gain @ H @ prior
    return float(np.sqrt(max(posterior[0, 0], 0.0))), float(np.sqrt(max(posterior[1, 1], 0.0)))


def causal_estimates(log: ModelLog, acceleration: np.ndarray) -> Estimates:
    """The observer over each coordinate of the log; ``acceleration`` (samples,
    coordinates) sizes its bound (BOUND_MARGIN times its largest magnitude)."""
    from ..robot.native import observe_adaptive

    bound = BOUND_MARGIN * np.max(np.abs(acceleration), axis=0) + 1e-12
    out = observe_adaptive(log.q, log.step, bound, with_position=True)
    assert out.position is not None
    position_std = np.empty_like(out.noise)
    velocity_std = np.empty_like(out.noise)
    for omega in np.unique(out.bandwidth):
        where = out.bandwidth == omega
        sx, sv = kalman_std(float(omega), log.step)
        position_std[where] = sx * out.noise[where]
        velocity_std[where] = sv * out.noise[where]
    return Estimates(out.position, out.velocity, position_std, velocity_std, out.noise,
                     out.bandwidth)
