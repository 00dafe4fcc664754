"""Standard errors of the physically consistent parameters, propagated through the
optimum of the convex program of harness.robot.consistency.

At the optimum the link variables X_i are positive definite (the log-det keeps them
inside the cone), so the only constraints that can hold are the joint terms' bounds
u_k >= lower_k. On the other variables the optimum is a smooth function of the estimate:
with y the free coordinates (10 per link: X_i's symmetric entries; the joint terms off
their bounds), z = T y and the objective

    f(y) = ||M T y - b||^2 + 2 w sum_i (tr X_i - log det X_i) + w ||u||^2,

the stationarity condition grad f = 0 differentiated in b gives dy = H^-1 2 T^T M^T db,
H the Hessian of f (2 T^T M^T M T, plus 2 w tr(X^-1 E_k X^-1 E_l) per link, plus 2 w on
the free joint terms). With b = W (beta_hat - P fixed), the consistent base parameters
P A T y move by G = P A T H^-1 2 T^T M^T W per unit of beta_hat, and their covariance is
G C G^T (C the estimate's covariance). A term held at its bound does not move (standard
error 0 for it alone); the rule is the active set's at the optimum, as for bounded
least squares.
"""
from __future__ import annotations

import numpy as np

#: X's symmetric basis: E_kk and E_kl + E_lk (k < l), column-major vec (16, 10)
_PAIRS = [(k, k) for k in range(4)] + [(k, m) for k in range(4) for m in range(k + 1, 4)]


def _symmetric_basis() -> np.ndarray:
    basis = np.zeros((16, len(_PAIRS)))
    for column, (k, m) in enumerate(_PAIRS):
        E = np.zeros((4, 4))
        E[k, m] = E[m, k] = 1.0
        basis[:, column] = E.reshape(-1, order="F")
    return basis


def consistent_covariance(X: list[np.ndarray], free_terms: np.ndarray, weight: float,
                          M: np.ndarray, whiten: np.ndarray, A: np.ndarray,
                          projector: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """Covariance (r, r) of the consistent base parameters P pi at the optimum (module):
    X the links' optimal X_i (4 x 4 each), free_terms (u's length) True for the joint
    terms off their bounds, weight w = 1 / tolerance^2, M, whiten (W), A, projector (P)
    as in consistency.consistent_parameters, covariance (r, r) the estimate's."""
    basis = _symmetric_basis()
    links, terms = len(X), len(free_terms)
    free = np.flatnonzero(free_terms)
    T = np.zeros((16 * links + terms, 10 * links + len(free)))
    hessian_prior = np.zeros((T.shape[1], T.shape[1]))
    matrices = [column.reshape(4, 4, order="F") for column in basis.T]
    for j, x in enumerate(X):
        T[16 * j:16 * j + 16, 10 * j:10 * j + 10] = basis
        inverse = np.linalg.inv(x)
        products = [inverse @ E for E in matrices]
        block = np.array([[np.sum(p * q.T) for q in products] for p in products])
        hessian_prior[10 * j:10 * j + 10, 10 * j:10 * j + 10] = 2 * weight * block
    T[16 * links + free, 10 * links + np.arange(len(free))] = 1.0
    hessian_prior[10 * links:, 10 * links:] += 2 * weight * np.eye(len(free))
    MT = M @ T
    hessian = 2 * MT.T @ MT + hessian_prior
    gain = projector @ A @ T @ np.linalg.solve(hessian, 2 * MT.T @ whiten)
    out = gain @ covariance @ gain.T
    return 0.5 * (out + out.T)
