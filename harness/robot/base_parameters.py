"""Base parameters: the combinations of the standard parameters that the torques determine.

The regressor Y (n x 12 n) of a chain has linearly dependent columns (parameters
that never move the joints, or only in fixed combinations).  Stacking Y over random
states and a QR decomposition with column pivoting gives the rank r, a set of r
independent ("base") columns and the matrix K such that
    Y pi = Y_b beta,   Y_b = Y[:, base],   beta = pi[base] + K pi[dependent].
The identifiers (offline here, online regressor_identifier.c) estimate beta.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

LINK_NAMES = ("m", "mx", "my", "mz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
FRICTION_NAMES = ("fv", "fc")


def parameter_names(joint_names: list[str]) -> list[str]:
    """Names of the 12 n standard parameters, in the regressor's order."""
    return ([f"{j}.{p}" for j in joint_names for p in LINK_NAMES] +
            [f"{j}.{p}" for j in joint_names for p in FRICTION_NAMES])


@dataclass
class BaseParameters:
    base: np.ndarray        # indices of the base columns in pi, ascending (r,)
    dependent: np.ndarray   # the other unknown parameters' indices (d,)
    K: np.ndarray           # (r, d): beta = pi[base] + K pi[dependent]
    names: list[str]        # names of beta's entries (the base column's parameter)
    dependent_names: list[str]

    @property
    def count(self) -> int:
        return len(self.base)

    def project(self, pi: np.ndarray) -> np.ndarray:
        """beta of a standard parameter vector pi."""
        return pi[..., self.base] + pi[..., self.dependent] @ self.K.T

    def regressor(self, Y: np.ndarray) -> np.ndarray:
        """Y_b from full regressors (..., 12 n)."""
        return Y[..., self.base]

    def description(self, index: int) -> str:
        """beta_index as a readable sum of standard parameters."""
        terms = [self.names[index]]
        for k, coefficient in enumerate(self.K[index]):
            if abs(coefficient) > 1e-9:
                terms.append(f"{coefficient:+.6g} {self.dependent_names[k]}")
        return " ".join(terms)


def random_states(types: np.ndarray, count: int, rng: np.random.Generator):
    """Random (q, q', q'') of the joints: angles over a full turn, prismatic +-1 m."""
    n = len(types)
    span = np.where(np.asarray(types) == 1, 1.0, np.pi)
    return (rng.uniform(-1, 1, (count, n)) * span, rng.normal(0, 2, (count, n)),
            rng.normal(0, 5, (count, n)))


def unknown_columns(n: int, unknown: str) -> np.ndarray:
    """The standard parameters to identify: "all", or "payload" (the last link's 10
    and the friction; the other links are taken as the URDF's)."""
    if unknown == "all":
        return np.arange(12 * n)
    if unknown == "payload":
        return np.concatenate([np.arange(10 * (n - 1), 10 * n), np.arange(10 * n, 12 * n)])
    raise ValueError(f"unknown parameters {unknown!r}: 'all' or 'payload'")


def base_parameters(body, types: np.ndarray, joint_names: list[str], unknown: str = "all",
                    samples: int = 400, seed: int = 0,
                    tolerance: float = 1e-9) -> BaseParameters:
    """Numerical base parameters of the C model `body` (harness.robot.native.RigidBody)
    among the `unknown` parameters (see unknown_columns); the others are not in K."""
    rng = np.random.default_rng(seed)
    columns = unknown_columns(len(types), unknown)
    Y = body.regressor(*random_states(types, samples, rng)).reshape(-1, body.parameter_count)
    Y = Y[:, columns]
    _, R, order = scipy.linalg.qr(Y, mode="economic", pivoting=True)
    diagonal = np.abs(np.diag(R))
    rank = int(np.sum(diagonal > tolerance * diagonal[0]))
    base_local = np.sort(order[:rank])
    dependent_local = np.setdiff1d(np.arange(len(columns)), base_local)
    base, dependent = columns[base_local], columns[dependent_local]
    Y = np.concatenate([Y[:, base_local], Y[:, dependent_local]], axis=1)
    # Y[:, dependent] = Y[:, base] K exactly (up to rounding): K by least squares
    K = np.linalg.lstsq(Y[:, :rank], Y[:, rank:], rcond=None)[0]
    K[np.abs(K) < 1e-10] = 0.0
    names = parameter_names(joint_names)
    return BaseParameters(base, dependent, K, [names[k] for k in base],
                          [names[k] for k in dependent])
