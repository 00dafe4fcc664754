"""The benchmark's baselines (bench/reports/realdata/baselines.py) on synthetic data with a known
answer: the FFT implementation equals the plain recursions, the estimators recover the
derivatives of a sine, least squares recovers exact parameters."""
from __future__ import annotations

import numpy as np
from scipy.signal import savgol_filter

from bench.reports.realdata import baselines as bl

H = 1e-3
T = np.arange(0.0, 6.0, H)
W = 2 * np.pi * 0.8  # rad/s
X, V, A = np.sin(W * T), W * np.cos(W * T), -W * W * np.sin(W * T)
AFTER = T >= 1.0


def test_fft_filter_and_smoother_equal_the_plain_recursions():
    y = X[:3000] + np.random.default_rng(1).normal(0.0, 1e-4, 3000)
    lam = 1e-9
    ss = bl.SteadyState.of(lam)
    s, xf = np.zeros(3), np.zeros((len(y), 3))
    for k, yk in enumerate(y - y[0]):  # x_k = (I - K H) F x_{k-1} + K y_k
        s = ss.A @ s + ss.K * yk
        xf[k] = s
    xs = xf.copy()
    for k in range(len(y) - 2, -1, -1):  # x^s_k = x_k + G (x^s_{k+1} - F x_k)
        xs[k] = xf[k] + ss.G @ (xs[k + 1] - bl.F @ xf[k])
    _, vf, af = bl.kalman(y, H, lam)
    _, vs, as_ = bl.rts(y, H, lam)
    assert np.max(np.abs(vf - xf[:, 1] / H)) < 1e-9
    assert np.max(np.abs(af - xf[:, 2] / H**2)) < 1e-7
    assert np.max(np.abs(vs - xs[:, 1] / H)) < 1e-9
    assert np.max(np.abs(as_ - xs[:, 2] / H**2)) < 1e-7


def test_kalman_rts_and_savgol_recover_the_velocity_of_a_sine():
    y = X + np.random.default_rng(2).normal(0.0, 1e-5, len(X))
    lam = bl.lambda_of(q=1e4, h=H, r=1e-10)
    for name, v in [("kalman", bl.kalman(y, H, lam)[1]), ("rts", bl.rts(y, H, lam)[1]),
                    ("savgol", bl.savgol(y, H, 41, 3, 1))]:
        rms = np.sqrt(np.mean((v - V)[AFTER] ** 2))
        assert rms < 2e-3 * W, (name, rms)  # 0.2 % of the velocity amplitude
    accel = bl.rts(X, H, bl.lambda_of(1e4, H, 1e-14))[2]
    assert np.max(np.abs(accel - A)[AFTER & (T < 5.0)]) < 1e-2 * W * W


def test_fast_savgol_is_scipy_savgol_filter():
    y = X + np.random.default_rng(3).normal(0.0, 1e-3, len(X))
    for window in (5, 101, 1001):
        for deriv in (1, 2):
            ours = bl.savgol(y, H, window, 3, deriv)
            ref = savgol_filter(y, window, 3, deriv=deriv, delta=H, mode="interp")
            assert np.max(np.abs(ours - ref)) < 1e-9 * max(1.0, np.max(np.abs(ref)))


def test_least_squares_recovers_exact_parameters():
    theta = np.array([1.12, 5.45, 0.20, 0.51])  # b, c1, c2, c3
    u = 3 * np.cos(2.3 * T) + np.sin(7.1 * T)
    acc = bl.regressor(u, X, V) @ theta
    assert np.max(np.abs(bl.least_squares(acc, u, X, V) / theta - 1)) < 1e-6
    times, path = bl.growing_least_squares(T, acc, u, X, V, start=1.0, every=0.05)
    assert times[-1] == T[-1]
    assert np.max(np.abs(path[-1] / theta - 1)) < 1e-6
