"""Physically consistent link parameters from identified base parameters, and the identified URDF.

Identification determines only the base parameters beta.  Among the standard
parameters pi that reproduce them, the ones written to the URDF are found by a
nonlinear least-squares fit over a parametrization that is physically consistent
by construction (log-Cholesky): per link, the pseudo-inertia
    J = [[Sigma, h], [h^T, m]] = L L^T,  Sigma = tr(I_o)/2 * 1 - I_o,
with L lower triangular with positive (exponential) diagonal, is positive definite:
m > 0 and an inertia about the centre of mass that is positive definite and satisfies
the triangle inequalities.  Friction is the square of its coordinate: >= 0.

The fit minimizes D + w P:
- D = (beta(pi) - beta_hat)^T C^-1 (beta(pi) - beta_hat), the estimate's Mahalanobis
  distance under its full (sandwich) covariance C: correlated base parameters move
  together as the data allow, not each within its own standard error;
- P = sum_k ((pi_k - pi_urdf_k) / (tolerance * scale_k))^2, the URDF as a prior: each
  parameter within +-tolerance of its scale (prior_scales: the URDF's value, the link's
  mass and size, or what the data make of the parameter, never an absolute floor);
- w = 1 (the prior at the stated tolerance) unless that takes beta(pi) out of the
  estimate's 95 % confidence region (D > chi2_r(0.95), widened by the distance of the
  nearest consistent point when even that lies outside) or makes the training-log
  prediction more than PREDICTION_MARGIN worse than the estimate's (when the pipeline
  passes its score: the sandwich covariance of a log whose residual is mostly model
  error, not noise, is wide): then the largest w < 1 (bisection in log w) that keeps
  it inside.  The prior decides what the data leave open and never outweighs what they
  determine.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.stats
from lxml import etree

from .base_parameters import BaseParameters
from .joint_terms import JointTerms
from .urdf import Robot, UrdfError, body_inertial, check_inertia, inertia_matrix, parse_urdf

# the default relative tolerance of the URDF's values (--urdf-tolerance):
# docs/design/robots.md explains the choice
DEFAULT_URDF_TOLERANCE = 0.3
CONFIDENCE = 0.95        # of the region the consistent parameters stay in
MIN_PRIOR_WEIGHT = 1e-8  # the weakest prior tried (it still picks the unidentified values)
WEIGHT_HALVINGS = 6      # bisection steps in log w (to 1/8 of a decade) when w = 1 leaves
# relative standard deviation added to each base parameter's: no estimate is taken as
# more precise than this (a noise-free log's would make the fit needlessly stiff; the
# training-log bound PREDICTION_MARGIN still holds the result to the estimate's fit)
COVARIANCE_FLOOR = 1e-4
PREDICTION_MARGIN = 0.02  # relative: the training-log error allowed above the estimate's


@dataclass
class Projection:
    """The consistent parameters and how close they stay to the estimate."""

    pi: np.ndarray          # consistent parameters (12 n standard, then the joint terms)
    distance: float         # D: Mahalanobis distance^2 of beta(pi) from the estimate
    nearest: float          # D of the nearest consistent point (NaN: not needed)
    bound: float            # D allowed: chi2_r(CONFIDENCE) (+ nearest, if computed)
    prior_weight: float     # w: 1 = the URDF at the stated tolerance
    tolerance: float        # the stated relative tolerance of the URDF's values
    error: float            # score(beta(pi)): the training-log error (0 without a score)
    error_bound: float      # the training-log error allowed


def pseudo_inertia(link: np.ndarray) -> np.ndarray:
    m, h, I = link[0], link[1:4], inertia_matrix(link[4:])
    J = np.empty((4, 4))
    J[:3, :3] = 0.5 * np.trace(I) * np.eye(3) - I
    J[:3, 3] = J[3, :3] = h
    J[3, 3] = m
    return J


def link_of_pseudo_inertia(J: np.ndarray) -> np.ndarray:
    """The 10 link parameters of a pseudo-inertia J (4 x 4), or of a stack of them
    (..., 4, 4) -> (..., 10)."""
    S, h, m = J[..., :3, :3], J[..., :3, 3], J[..., 3, 3]
    trace = S[..., 0, 0] + S[..., 1, 1] + S[..., 2, 2]
    return np.stack([m, h[..., 0], h[..., 1], h[..., 2], trace - S[..., 0, 0], -S[..., 0, 1],
                     trace - S[..., 1, 1], -S[..., 0, 2], -S[..., 1, 2], trace - S[..., 2, 2]],
                    axis=-1)


_LOWER = np.tril_indices(4)
_DIAGONAL = [k for k, (r, c) in enumerate(zip(*_LOWER)) if r == c]


def _log_cholesky(link: np.ndarray) -> np.ndarray:
    """The 10 log-Cholesky coordinates of a (near-)consistent link, made strictly
    consistent first (a small multiple of the identity added if needed)."""
    J = pseudo_inertia(link)
    scale = max(np.abs(J).max(), 1e-6)
    shift = max(0.0, 1e-6 * scale - np.linalg.eigvalsh(J)[0])
    L = np.linalg.cholesky(J + shift * np.eye(4))
    theta = L[_LOWER].copy()
    theta[_DIAGONAL] = np.log(theta[_DIAGONAL])
    return theta


def _link(theta: np.ndarray) -> np.ndarray:
    L = np.zeros((4, 4))
    values = theta.copy()
    values[_DIAGONAL] = np.exp(np.clip(values[_DIAGONAL], -50.0, 50.0))
    L[_LOWER] = values
    return link_of_pseudo_inertia(L @ L.T)


def prior_scales(nominal: np.ndarray, n: int, data_scale: np.ndarray) -> np.ndarray:
    """The scale of each standard parameter (12 n, then any extra joint terms': nominal
    and data_scale as long) that the URDF tolerance multiplies.

    Link i (URDF mass m > 0, size l = sqrt(tr I_o / 2m) from its inertia about the joint
    frame): the larger of |the URDF's value| and m (mass), m l (first moments), m l^2
    (inertias), so that a zero first moment or product of inertia is not pinned at 0.
    A link without mass in the URDF and the friction: the larger of |the URDF's value|
    and data_scale, what the data make of the parameter (the value that alone would
    explain the measured torques: |u| / |Y_k| over the regression's equations).  A
    parameter that neither the URDF nor the data give a scale to gets 1 (it moves no
    joint and the URDF leaves it at 0).  The extra joint terms are scaled like the
    friction."""
    nominal = np.asarray(nominal, float)
    data_scale = np.asarray(data_scale, float)
    physical = np.full(len(nominal), np.nan)  # 12 n, and the extra joint terms
    for i in range(n):
        link = nominal[10 * i:10 * i + 10]
        mass = link[0]
        trace = link[4] + link[6] + link[9]
        if mass > 0 and trace > 0:
            size = np.sqrt(trace / (2 * mass))
            physical[10 * i:10 * i + 10] = [mass, *[mass * size] * 3, *[mass * size ** 2] * 6]
    fallback = np.where(np.isfinite(data_scale) & (data_scale > 0), data_scale, np.nan)
    physical = np.where(np.isnan(physical), fallback, physical)
    scale = np.fmax(np.abs(nominal), physical)
    return np.where(np.isfinite(scale) & (scale > 0), scale, 1.0)


def _link_jacobian(theta: np.ndarray) -> np.ndarray:
    """d _link(theta) / d theta (10 x 10): J = L L^T, dJ = E L^T + L E^T with E the
    derivative of L along one coordinate, and the link parameters linear in J (all ten
    coordinates at once)."""
    L = np.zeros((4, 4))
    values = theta.copy()
    values[_DIAGONAL] = np.exp(np.clip(values[_DIAGONAL], -50.0, 50.0))
    L[_LOWER] = values
    E = np.zeros((10, 4, 4))
    E[_COORDINATES, _LOWER[0], _LOWER[1]] = _coordinate_steps(values)
    dJ = E @ L.T
    return link_of_pseudo_inertia(dJ + dJ.transpose(0, 2, 1)).T


_COORDINATES = np.arange(10)


def _coordinate_steps(values: np.ndarray) -> np.ndarray:
    """dL_rc / d theta_k: the value itself on the diagonal (log coordinates), else 1."""
    step = np.ones(10)
    step[_DIAGONAL] = values[_DIAGONAL]
    return step


def consistent_parameters(robot: Robot, base: BaseParameters, beta: np.ndarray,
                          covariance: np.ndarray, data_scale: np.ndarray | None = None,
                          tolerance: float = DEFAULT_URDF_TOLERANCE,
                          score: Callable[[np.ndarray], float] | None = None,
                          terms: JointTerms | None = None) -> Projection:
    """Standard parameters pi (12 n) that are physically consistent, keep beta(pi) in
    the estimate's confidence region (covariance (r, r) of beta) and are as close to
    the URDF's values as `tolerance` (relative, > 0) says where the data allow (see the
    module's description).  data_scale (12 n): see prior_scales (None: the URDF's
    values and link sizes alone).  score(beta), if given, is the training-log prediction
    error of base parameters beta: the prior is weakened also where it would make it more
    than PREDICTION_MARGIN (relative) larger than the estimate's (or the nearest
    consistent point's, if that is larger).  Only the links and friction among the
    identified (base and dependent) columns move.

    terms (harness.robot.joint_terms): the extra joint terms after the 12 n standard
    parameters (pi then has 12 n + terms.count(n) entries): kept out of the links, the
    offsets free, the armature and the Coulomb levels >= 0 (squared coordinates like the
    friction), their prior 0 (the URDF has none) at the data's scale."""
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise ValueError(f"the URDF tolerance must be a finite number > 0, not {tolerance!r}")
    n = robot.n
    terms = terms or JointTerms()
    extra = terms.count(n)
    size = 12 * n + extra
    nominal = np.concatenate([robot.parameters(), np.zeros(extra)])
    free = np.union1d(base.base, base.dependent)
    links = sorted({int(k) // 10 for k in free if k < 10 * n})
    signed = np.flatnonzero(~terms.nonnegative(n)) + 12 * n  # the offsets
    friction = np.array([k for k in free if k >= 10 * n and k not in signed], dtype=int)
    offsets = np.array([k for k in free if k in signed], dtype=int)
    whiten = _whitening(beta, covariance)
    if data_scale is None:
        data_scale = np.full(size, np.nan)
    scales = prior_scales(nominal, n, data_scale)
    prior = 1.0 / (tolerance * scales[free])
    squares = slice(10 * len(links), 10 * len(links) + len(friction))
    linear = slice(squares.stop, None)

    def unpack(x: np.ndarray) -> np.ndarray:
        pi = nominal.copy()
        for j, i in enumerate(links):
            pi[10 * i:10 * i + 10] = _link(x[10 * j:10 * j + 10])
        pi[friction] = x[squares] ** 2  # >= 0
        pi[offsets] = x[linear]
        return pi

    def derivative(x: np.ndarray) -> np.ndarray:
        """d pi / d x (size, len(x))."""
        D = np.zeros((size, len(x)))
        for j, i in enumerate(links):
            D[10 * i:10 * i + 10, 10 * j:10 * j + 10] = _link_jacobian(x[10 * j:10 * j + 10])
        D[friction, 10 * len(links) + np.arange(len(friction))] = 2 * x[squares]
        D[offsets, squares.stop + np.arange(len(offsets))] = 1.0
        return D

    projector = whiten @ base.project(np.eye(size)).T  # W P: whitened beta of pi

    def data_residual(x: np.ndarray) -> np.ndarray:
        return projector @ unpack(x) - whitened_beta

    whitened_beta = whiten @ beta

    def solve(weight: float, start: np.ndarray) -> tuple[np.ndarray, float]:
        root = np.sqrt(weight)

        def residual(x: np.ndarray) -> np.ndarray:
            pi = unpack(x)
            return np.concatenate([projector @ pi - whitened_beta,
                                   root * prior * (pi - nominal)[free]])

        def jacobian(x: np.ndarray) -> np.ndarray:
            D = derivative(x)
            return np.vstack([projector @ D, (root * prior)[:, None] * D[free]])

        # the search may try steps far out (a square of a large friction coordinate
        # overflows there): such a step is rejected by its residual, not worth a warning
        with np.errstate(over="ignore", invalid="ignore"):
            x = scipy.optimize.least_squares(residual, start, jac=jacobian, method="lm",
                                             x_scale="jac", max_nfev=4000).x
        return x, float(np.sum(data_residual(x) ** 2))

    # friction from the base estimate directly (its columns are always base columns),
    # as the square root of a value > 0: a zero would have no gradient
    value = np.maximum(nominal[friction], 0.0)
    for k, column in enumerate(friction):
        if column in base.base:
            value[k] = max(beta[list(base.base).index(column)], 0.0)
    value = np.maximum(value, 1e-6 * scales[friction])
    offset = np.array([beta[list(base.base).index(k)] if k in base.base else 0.0
                       for k in offsets])
    start = np.concatenate([*(_log_cholesky(nominal[10 * i:10 * i + 10]) for i in links),
                            np.sqrt(value), offset])
    region = float(scipy.stats.chi2.ppf(CONFIDENCE, len(beta)))
    error = score or (lambda _: 0.0)

    def model_error(x: np.ndarray) -> float:
        return error(base.project(unpack(x)))

    # w = 1: the prior at the stated tolerance
    x, distance = solve(1.0, start)
    error_bound = (1 + PREDICTION_MARGIN) * error(beta)
    if distance <= region and model_error(x) <= error_bound:
        return Projection(unpack(x), distance, float("nan"), region, 1.0, tolerance,
                          model_error(x), error_bound)
    # it leaves the region: how far is the nearest consistent point (w -> 0), and how much
    # prior keeps the model within the region around it
    best, nearest = solve(MIN_PRIOR_WEIGHT, x)
    bound = nearest + region
    error_bound = max(error_bound, (1 + PREDICTION_MARGIN) * model_error(best))
    weight, best_distance = MIN_PRIOR_WEIGHT, nearest
    if distance <= bound and model_error(x) <= error_bound:
        weight, best, best_distance = 1.0, x, distance
    else:
        low, high = np.log10(MIN_PRIOR_WEIGHT), 0.0
        for _ in range(WEIGHT_HALVINGS):
            middle = 0.5 * (low + high)
            trial, trial_distance = solve(10.0 ** middle, best)
            if trial_distance <= bound and model_error(trial) <= error_bound:
                low, best, best_distance = middle, trial, trial_distance
            else:
                high = middle
        weight = 10.0 ** low
    return Projection(unpack(best), best_distance, nearest, bound, weight, tolerance,
                      model_error(best), error_bound)


def _whitening(beta: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """W = L^-1 with L L^T the covariance, regularized so that exact (noise-free)
    estimates keep a finite weight: COVARIANCE_FLOOR of each |beta_k| (of that of 1e-6 of
    the largest for beta_k = 0) added in quadrature."""
    magnitude = np.abs(beta)
    floor = COVARIANCE_FLOOR * np.maximum(
        magnitude, 1e-6 * max(float(magnitude.max(initial=0.0)), 1e-300))
    C = np.asarray(covariance, float) + np.diag(floor ** 2)
    try:
        L = np.linalg.cholesky(0.5 * (C + C.T))
    except np.linalg.LinAlgError:  # not positive definite by rounding: the diagonal alone
        L = np.diag(np.sqrt(np.maximum(np.diag(C), floor ** 2)))
    return scipy.linalg.solve_triangular(L, np.eye(len(beta)), lower=True)


def write_identified_urdf(robot: Robot, pi: np.ndarray, path: Path, comment: str) -> None:
    """The robot's URDF with each body's identified inertial on the joint's child link
    (links merged into that body lose theirs: the body's inertial holds them) and
    <dynamics damping="viscous" friction="Coulomb"/> on each joint."""
    tree = parse_urdf(robot.source)  # as read_urdf parsed it: no entity, no DTD
    root = tree.getroot()
    root.insert(0, etree.Comment(f" {comment.replace('--', '- -')} "))
    links = {link.get("name"): link for link in root.findall("link")}
    joints = {joint.get("name"): joint for joint in root.findall("joint")}
    n = robot.n
    for i, joint in enumerate(robot.joints):
        mass, com, inertia = body_inertial(pi[10 * i:10 * i + 10])
        if not (np.isfinite(mass) and np.all(np.isfinite(com))
                and np.all(np.isfinite(inertia))):
            raise UrdfError(f"the identified link {joint.child_link!r} has a mass, centre of "
                            f"mass or inertia that is not finite: no URDF is written")
        check_inertia(inertia, f"identified link {joint.child_link!r}")
        for name in joint.merged_links:
            for element in links[name].findall("inertial"):
                links[name].remove(element)
        link = links[joint.child_link]
        for element in link.findall("inertial"):
            link.remove(element)
        if mass != 0.0 or np.any(inertia):  # a massless body stays without <inertial>
            _add_inertial(link, mass, com, inertia)
        element = joints[joint.name]
        for dynamics in element.findall("dynamics"):
            element.remove(dynamics)
        etree.SubElement(element, "dynamics", damping=f"{pi[10 * n + 2 * i]:.12g}",
                         friction=f"{pi[10 * n + 2 * i + 1]:.12g}")
    tree.write(str(path), xml_declaration=True, encoding="utf-8", pretty_print=True)


def _add_inertial(link, mass: float, com: np.ndarray, inertia: np.ndarray) -> None:
    """An <inertial> child of ``link``: the centre of mass, mass and inertia about it."""
    inertial = etree.SubElement(link, "inertial")
    etree.SubElement(inertial, "origin", xyz=" ".join(f"{x:.12g}" for x in com), rpy="0 0 0")
    etree.SubElement(inertial, "mass", value=f"{mass:.12g}")
    etree.SubElement(inertial, "inertia", **{
        key: f"{inertia[r, c]:.12g}" for key, (r, c) in
        {"ixx": (0, 0), "ixy": (0, 1), "ixz": (0, 2), "iyy": (1, 1), "iyz": (1, 2),
         "izz": (2, 2)}.items()})
