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

from .joint_terms import ARMATURE, COULOMB_NEGATIVE, COULOMB_POSITIVE, OFFSET, JointTerms
from .layout import ParameterLayout

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
        """beta of a parameter vector pi (12 n standard, then the extra joint terms)."""
        return pi[..., self.base] + pi[..., self.dependent] @ self.K.T

    def regressor(self, Y: np.ndarray) -> np.ndarray:
        """Y_b from full regressors (..., 12 n + the extra joint terms')."""
        return Y[..., self.base]

    def description(self, index: int) -> str:
        """beta_index as a readable sum of standard parameters."""
        terms = [self.names[index]]
        for k, coefficient in enumerate(self.K[index]):
            if abs(coefficient) > 1e-9:
                terms.append(f"{coefficient:+.6g} {self.dependent_names[k]}")
        return " ".join(terms)


#: the order in which the extra joint terms join the base (base_parameters)
EXTRA_PREFERENCE = (COULOMB_POSITIVE, COULOMB_NEGATIVE, ARMATURE, OFFSET)


def _independent_extras(Y: np.ndarray, chosen: np.ndarray, terms: JointTerms, n: int,
                        tolerance: float) -> np.ndarray:
    """The extra columns (0-based among the k n extras) that join the base: in the order
    of EXTRA_PREFERENCE, each whose part outside the span of the columns chosen so far
    (Y[:, chosen], then the extras taken) is more than sqrt(tolerance) of its norm."""
    k = len(terms.kinds)
    if k == 0:
        return np.zeros(0, dtype=int)
    Q = np.linalg.qr(Y[:, chosen])[0] if len(chosen) else np.zeros((len(Y), 0))
    taken = []
    rank = {kind: EXTRA_PREFERENCE.index(kind) for kind in terms.kinds}
    start = ParameterLayout(n, k).standard_size  # the extras' first column
    for j in sorted(range(k * n), key=lambda j: (rank[terms.kinds[j % k]], j)):
        column = Y[:, start + j]
        size = float(np.linalg.norm(column))
        for _ in range(2):  # projected twice: orthogonal to rounding
            column = column - Q @ (Q.T @ column)
        if size > 0 and np.linalg.norm(column) > np.sqrt(tolerance) * size:
            Q = np.column_stack([Q, column / np.linalg.norm(column)])
            taken.append(j)
    return np.array(sorted(taken), dtype=int)


def random_states(types: np.ndarray, count: int, rng: np.random.Generator):
    """Random (q, q', q'') of the joints: angles over a full turn, prismatic +-1 m."""
    n = len(types)
    span = np.where(np.asarray(types) == 1, 1.0, np.pi)
    return (rng.uniform(-1, 1, (count, n)) * span, rng.normal(0, 2, (count, n)),
            rng.normal(0, 5, (count, n)))


def unknown_columns(n: int, unknown: str) -> np.ndarray:
    """The standard parameters to identify: "all", or "payload" (the last link's 10
    and the friction; the other links are taken as the URDF's)."""
    layout = ParameterLayout(n)
    if unknown == "all":
        return layout.indices(layout.standard)
    if unknown == "payload":
        return np.concatenate([layout.indices(layout.link(n - 1)),
                               layout.indices(layout.friction)])
    raise ValueError(f"unknown parameters {unknown!r}: 'all' or 'payload'")


def base_parameters(body, types: np.ndarray, joint_names: list[str], unknown: str = "all",
                    samples: int = 400, seed: int = 0, tolerance: float = 1e-9,
                    terms: JointTerms | None = None) -> BaseParameters:
    """Numerical base parameters of the C model `body` (harness.robot.native.RigidBody)
    among the `unknown` parameters (see unknown_columns); the others are not in K.

    terms (harness.robot.joint_terms): the extra joint terms, columns 12 n onwards
    (all unknown; a core column they replace is neither base nor dependent).  The core's
    columns are chosen as without them; then each extra column joins the base unless the
    columns chosen already span it, the Coulomb levels and the armature before the
    offsets (EXTRA_PREFERENCE): an offset collinear with the asymmetric Coulomb levels
    is folded into them."""
    rng = np.random.default_rng(seed)
    n = len(types)
    terms = terms or JointTerms()
    layout = ParameterLayout(n, len(terms.kinds))
    columns = np.setdiff1d(unknown_columns(n, unknown), terms.replaced(n))
    q, qd, qdd = random_states(types, samples, rng)
    Y = terms.extend(body.regressor(q, qd, qdd), qd, qdd).reshape(-1, layout.size)
    _, R, order = scipy.linalg.qr(Y[:, columns], mode="economic", pivoting=True)
    diagonal = np.abs(np.diag(R))
    rank = int(np.sum(diagonal > tolerance * diagonal[0]))
    base_local = np.sort(order[:rank])
    extra = _independent_extras(Y, columns[base_local], terms, n, tolerance)
    columns = np.concatenate([columns, layout.indices(layout.extra)])
    base_local = np.sort(np.concatenate([base_local, len(columns) - terms.count(n) + extra]))
    rank = len(base_local)
    Y = Y[:, columns]
    dependent_local = np.setdiff1d(np.arange(len(columns)), base_local)
    base, dependent = columns[base_local], columns[dependent_local]
    Y = np.concatenate([Y[:, base_local], Y[:, dependent_local]], axis=1)
    # Y[:, dependent] = Y[:, base] K exactly (up to rounding): K by least squares
    K = np.linalg.lstsq(Y[:, :rank], Y[:, rank:], rcond=None)[0]
    K[np.abs(K) < 1e-10] = 0.0
    names = parameter_names(joint_names) + terms.names(joint_names)
    return BaseParameters(base, dependent, K, [names[k] for k in base],
                          [names[k] for k in dependent])
