"""Offline torque-space least squares over base regressors, with standard errors."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Fit:
    beta: np.ndarray           # (r,) estimate
    std_error: np.ndarray      # (r,) sandwich standard errors
    residual_rms: np.ndarray   # (n,) per joint
    condition: float           # of the weighted regression matrix
    covariance: np.ndarray     # (r, r) sandwich covariance of beta

    def relative_errors(self, truth: np.ndarray) -> np.ndarray:
        return np.abs(self.beta - truth) / np.maximum(np.abs(truth), 1e-12)


def torque_least_squares(Yb: np.ndarray, z: np.ndarray, batch: int = 1,
                         mask: np.ndarray | None = None) -> Fit:
    """beta minimizing sum_k |W (z_k - Yb_k beta)|^2 over samples k.

    Yb: (N, n, r) base regressors, z: (N, n) torques (or torque residuals).
    W = diag(1 / sigma_i) with sigma_i the residual RMS of joint i after an
    unweighted first pass, so that each joint counts by its fit, not its scale.
    Standard errors by the sandwich (A^T A)^-1 S (A^T A)^-1 with S summed over
    batches of `batch` consecutive samples (residuals correlated over fewer
    samples than a batch, e.g. filtered signals, are accounted for).
    mask (N, n): the joint equations to use (False leaves that joint's row of that
    sample out, e.g. near its velocity reversals)."""
    N, n, r = Yb.shape
    if mask is not None:  # a left-out row is a row of zeros: no information, no residual
        Yb, z = Yb * mask[:, :, None], z * mask
    if N * n < r:
        raise ValueError(f"{N} samples of {n} joints cannot determine {r} parameters")
    scale = np.ones(n)
    for weighted in (False, True):
        A = Yb / scale[None, :, None]
        beta, *_ = np.linalg.lstsq(A.reshape(-1, r), (z / scale[None, :]).ravel(), rcond=None)
        residual = z - np.einsum("kij,j->ki", Yb, beta)
        used = mask.sum(axis=0) if mask is not None else np.full(n, N)
        rms = np.sqrt(np.sum(residual ** 2, axis=0) / np.maximum(used, 1))
        if not weighted:  # noise-free joints keep a scale relative to the others
            scale = np.maximum(rms, 1e-9 * rms.max()) if rms.max() > 0 else np.ones(n)
    information = np.einsum("kia,kib->ab", A, A)
    scores = np.einsum("kia,ki->ka", A, residual / scale[None, :])
    usable = N // batch * batch
    batch_scores = scores[:usable].reshape(-1, batch, r).sum(axis=1)
    S = batch_scores.T @ batch_scores * (N / max(usable, 1))
    gamma = np.linalg.inv(information)
    covariance = gamma @ S @ gamma
    covariance = 0.5 * (covariance + covariance.T)
    std = np.sqrt(np.maximum(np.diag(covariance), 0.0))
    return Fit(beta, std, rms, float(np.linalg.cond(A.reshape(-1, r))), covariance)
