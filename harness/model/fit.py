"""Least squares on a model's regressor rows, regularized relative to each column's scale,
with standard errors from the residuals and an excitation figure per unknown: the one
least squares of every identification path (model files and robots).

Each column k of Y is divided by its RMS s_k (:func:`harness.model.rms_columns`), so
the unknowns solved for are phi_k = s_k theta_k, each the size of its term in the
equations. The ridge term pulls phi toward the nominal s_k theta_nominal with the same
weight for every unknown: changing a file's units rescales a column and its unknown
inversely and leaves phi, and so every physical value, as it was.
"""
from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import ParamSpec, TypeVar

import numpy as np
import scipy.optimize

from .numeric import rms_columns

#: Ridge weight relative to the mean diagonal of the normalized normal equations: it
#: keeps a nearly collinear problem solvable and moves a well-excited unknown by about
#: RIDGE / excitation^2 of its scale.
RIDGE = 1e-9
#: Consecutive samples whose residuals may be correlated (the sandwich's batches): 100
#: samples (0.1 s at 1 kHz; 10 rows of a pipeline decimated by 10). On EMPS the residuals
#: (model error, not white noise) are correlated over tens of ms: the standard errors of
#: batches of 1 decimated row are up to 2.3 times smaller.
BATCH_SAMPLES = 100
P = ParamSpec("P")
R = TypeVar("R")


@dataclass(frozen=True)
class Fit:
    """An identification: values and standard errors in the file's units, per unknown."""

    theta: np.ndarray
    std_error: np.ndarray       # sandwich, 1 sigma
    classical_error: np.ndarray  # residual variance times (Y'Y)^-1, 1 sigma
    excitation: np.ndarray      # per unknown, 0 (absent or collinear) .. 1 (orthogonal)
    equation_rms: np.ndarray    # residual RMS per equation (SI), over the rows used
    rows: int
    covariance: np.ndarray      # sandwich covariance of theta (p, p)
    condition: float            # of the weighted regressor with its columns normalized
    #: per unknown: -1 held at the lower end of its declared range, 1 at the upper, 0 free
    #: (a held unknown has standard error 0: the range, not the log, sets it)
    at_bound: np.ndarray | None = None
    unbounded: np.ndarray | None = None  # the estimate without the ranges (when one holds)
    unbounded_std: np.ndarray | None = None  # and its sandwich standard errors


def _excitation(gram: np.ndarray) -> np.ndarray:
    """How far each unknown's column stands out of the others: |part of column k not
    explained by the other columns| / |column k|, i.e. sqrt(1 - R_k^2) (1/sqrt of the
    variance inflation factor); 0 for a column that is zero on the log or a combination of
    the others. From the columns' Gram matrix ``gram``: each column's regression on the
    others is solved in the p x p normal equations (a long log costs one pass over its
    rows, not one per unknown)."""
    norms = np.sqrt(np.maximum(np.diag(gram), 0.0))
    present = norms > 0
    G = gram / np.outer(np.where(present, norms, 1.0), np.where(present, norms, 1.0))
    out = np.zeros(len(G))
    for k in np.flatnonzero(present):
        others = np.flatnonzero(present & (np.arange(len(G)) != k))
        explained = 0.0
        if others.size:
            coefficients, *_ = np.linalg.lstsq(G[np.ix_(others, others)], G[others, k],
                                               rcond=None)
            explained = float(G[others, k] @ coefficients)
        out[k] = np.sqrt(max(1.0 - explained, 0.0))
    return out


def _weighted(Y: np.ndarray, weights: np.ndarray | None) -> np.ndarray:
    return Y if weights is None else Y / weights[None, :, None]


def _overflow_unsaid(function: Callable[P, R]) -> Callable[P, R]:
    """Values so large that the sums overflow give non-finite figures, which the callers
    refuse by name: numpy's warnings would only repeat it."""
    @functools.wraps(function)
    def quiet(*args: P.args, **kwargs: P.kwargs) -> R:
        with np.errstate(over="ignore", invalid="ignore"):
            return function(*args, **kwargs)
    return quiet


@_overflow_unsaid
def fit(Y: np.ndarray, r: np.ndarray, nominal: np.ndarray, ridge: float = RIDGE,
        batch: int = BATCH_SAMPLES, mask: np.ndarray | None = None,
        bounds: tuple[np.ndarray, np.ndarray] | None = None) -> Fit:
    """theta minimizing sum over rows and equations of (W (Y theta - r))^2 plus the
    relative ridge toward ``nominal``. With several equations, W weighs each by 1 / its
    residual RMS after an unweighted pass, so that equations in different units count by
    their fit. Standard errors: the sandwich (H^-1 S H^-1, S from the residual scores
    summed over ``batch`` consecutive rows: pass BATCH_SAMPLES / the rows' decimation) and
    the classical residual-variance ones. ``mask`` (rows, equations): the equations to use
    (False leaves that equation of that row out: no information, no residual).
    ``bounds`` (lower, upper per unknown, +-inf for none): the minimum inside that box
    (:func:`_bounded`); the standard errors of the free unknowns are then those with the
    held ones fixed."""
    if mask is not None:
        Y, r = Y * mask[:, :, None], r * mask
    rows, equations, p = Y.shape
    used = _used(Y, mask)
    scales, weights, theta, H, information, Z, rw, rms = _weighted_solve(Y, r, nominal, ridge,
                                                                       used)
    unbounded, at_bound = None, np.zeros(p, dtype=int)
    if bounds is not None and _outside(theta, bounds):
        unbounded = theta
        theta, at_bound = _bounded(theta, H, scales, bounds)
    free = at_bound == 0
    residual_w = rw - Z @ (theta * scales)  # (rows, equations)
    H_inv = np.zeros((p, p))
    H_inv[np.ix_(free, free)] = np.linalg.inv(H[np.ix_(free, free)])
    scores = np.einsum("sek,se->sk", Z, residual_w)
    usable = rows // batch * batch
    batched = scores[:usable].reshape(-1, batch, p).sum(axis=1)
    S = batched.T @ batched * (rows / max(usable, 1))
    covariance = H_inv @ S @ H_inv / np.outer(scales, scales)
    covariance = 0.5 * (covariance + covariance.T)
    sandwich = np.sqrt(np.maximum(np.diag(covariance), 0.0))
    unbounded_std = None
    if unbounded is not None:  # how far outside the range the log puts a held unknown
        H_all = np.linalg.inv(H)
        unbounded_std = np.sqrt(np.maximum(np.diag(H_all @ S @ H_all), 0.0)) / scales
    variance = float(np.sum(residual_w ** 2)) / max(float(used.sum()) - int(free.sum()), 1.0)
    classical = np.sqrt(np.maximum(variance * np.diag(H_inv @ information @ H_inv), 0.0)) \
        / scales
    return Fit(theta, sandwich, classical, _excitation(information), rms, rows, covariance,
               _condition(information), at_bound if unbounded is not None else None,
               unbounded, unbounded_std)


def expanded(part: Fit, free: np.ndarray, excitation: np.ndarray,
             others: np.ndarray | None = None) -> Fit:
    """A fit of the unknowns ``free`` as one of every unknown: the others at ``others``
    (None: 0) with standard error 0, their excitation from ``excitation`` (a fit of every
    unknown)."""
    def full(values: np.ndarray, rest: np.ndarray | None = None) -> np.ndarray:
        out = np.zeros(len(free)) if rest is None else np.array(rest, dtype=float)
        out[free] = values
        return out
    covariance = np.zeros((len(free), len(free)))
    covariance[np.ix_(free, free)] = part.covariance
    return Fit(full(part.theta, others), full(part.std_error), full(part.classical_error),
               np.where(free, full(part.excitation), excitation), part.equation_rms, part.rows,
               covariance, part.condition,
               None if part.at_bound is None else full(part.at_bound).astype(int),
               None if part.unbounded is None else full(part.unbounded, others),
               None if part.unbounded_std is None else full(part.unbounded_std))


def _outside(theta: np.ndarray, bounds: tuple[np.ndarray, np.ndarray]) -> bool:
    lower, upper = bounds
    return bool(np.any(theta < lower) or np.any(theta > upper))


def _bounded(theta: np.ndarray, H: np.ndarray, scales: np.ndarray,
             bounds: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The least squares inside the box: the regularized objective is
    (phi - phi_hat)' H (phi - phi_hat) plus a constant in the normalized unknowns, so the
    box's minimum is the bounded linear least squares of L' (phi - phi_hat), H = L L'
    (scipy's bounded-variable least squares: an exact active set). Returns theta and
    which end holds each unknown (-1, 1; 0 free)."""
    lower, upper = bounds
    L = np.linalg.cholesky(H)
    phi_hat = theta * scales
    result = scipy.optimize.lsq_linear(L.T, L.T @ phi_hat, bounds=(lower * scales,
                                                                   upper * scales),
                                       method="bvls", tol=1e-14)
    held = np.asarray(result.active_mask, dtype=int)
    out = np.where(held < 0, lower, np.where(held > 0, upper, result.x / scales))
    return out, held


def _condition(information: np.ndarray) -> float:
    """The condition number of the regressor whose normal matrix is ``information``."""
    eigenvalues = np.linalg.eigvalsh(information)
    return float(np.sqrt(eigenvalues[-1] / eigenvalues[0])) if eigenvalues[0] > 0 \
        else float("inf")


@_overflow_unsaid
def estimate(Y: np.ndarray, r: np.ndarray, nominal: np.ndarray, ridge: float = RIDGE,
             mask: np.ndarray | None = None,
             bounds: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """The values of :func:`fit` alone (no standard errors, no excitation)."""
    if mask is not None:
        Y, r = Y * mask[:, :, None], r * mask
    scales, _, theta, H, *_ = _weighted_solve(Y, r, nominal, ridge, _used(Y, mask))
    if bounds is not None and _outside(theta, bounds):
        theta = _bounded(theta, H, scales, bounds)[0]
    return theta


def _used(Y: np.ndarray, mask: np.ndarray | None) -> np.ndarray:
    """The rows each equation uses (every row without a mask)."""
    rows, equations = Y.shape[:2]
    return (np.full(equations, float(rows)) if mask is None else
            np.maximum(mask.sum(axis=0), 1).astype(float))


def _weighted_solve(Y: np.ndarray, r: np.ndarray, nominal: np.ndarray, ridge: float,
                    used: np.ndarray) -> tuple[np.ndarray, ...]:
    """:func:`_solve` with the equations weighted by their residual RMS over their ``used``
    rows (two passes when there are several equations); also returns the scales, weights
    and residual RMS (the plain normal matrix is the fit's information: built once)."""
    rows, equations, p = Y.shape
    if used.sum() <= p:
        raise ValueError(f"{int(used.sum())} equations ({rows} rows of {equations}) cannot "
                         f"determine {p} unknowns")
    scales = rms_columns(Y)
    scales = np.where(scales > 0, scales, 1.0)
    weights = np.ones(equations)
    for _ in range(2 if equations > 1 else 1):
        theta, H, information, Z, rw = _solve(Y, r, nominal, scales, weights, ridge)
        residual = r - Y @ theta
        rms = np.sqrt(np.sum(residual ** 2, axis=0) / used)
        if equations > 1 and rms.max() > 0:
            weights = np.maximum(rms, 1e-9 * rms.max())
    return scales, weights, theta, H, information, Z, rw, rms


def _solve(Y: np.ndarray, r: np.ndarray, nominal: np.ndarray, scales: np.ndarray,
           weights: np.ndarray, ridge: float
           ) -> tuple[np.ndarray, ...]:
    """The regularized normal equations in the normalized unknowns phi = scales * theta:
    theta, the regularized and the plain normal matrix, the normalized rows and sides."""
    Z = _weighted(Y, weights) / scales[None, None, :]
    rw = r / weights[None, :]
    flat = Z.reshape(-1, Z.shape[2])  # one matrix product: BLAS, not an einsum loop
    A = flat.T @ flat
    b = flat.T @ rw.reshape(-1)
    # relative to the rows' size; a regressor that is zero on the whole log (a coordinate
    # that never moves) keeps the nominal values, for the excitation check to name
    lam = ridge * (float(np.mean(np.diag(A))) or 1.0)
    H = A + lam * np.eye(len(scales))
    phi = np.linalg.solve(H, b + lam * scales * nominal)
    return phi / scales, H, A, Z, rw


def relative_errors(Y: np.ndarray, r: np.ndarray, theta: np.ndarray
                    ) -> tuple[list[float | None], float]:
    """|Y theta - r| / |r| per equation (None where r is zero on the log) and pooled over
    all equations."""
    with np.errstate(all="ignore"):  # an overflow is a non-finite figure, refused by the caller
        error = Y @ theta - r
        per = [float(np.linalg.norm(error[:, i]) / np.linalg.norm(r[:, i]))
               if np.linalg.norm(r[:, i]) > 0 else None for i in range(r.shape[1])]
        total = float(np.linalg.norm(r))
        pooled = float(np.linalg.norm(error) / total) if total > 0 else float("inf")
    return per, pooled
