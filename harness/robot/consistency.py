"""Physically consistent link parameters from identified base parameters, and the identified URDF.

Identification determines only the base parameters beta.  Among the standard
parameters pi that reproduce them, the ones written to the URDF solve a convex
program (cvxpy, solved by Clarabel).  Per identified link the variable is its
pseudo-inertia
    J = [[Sigma, h], [h^T, m]],  Sigma = tr(I_o)/2 * 1 - I_o,
and J >> 0 (positive semidefinite) is exactly the condition that some mass density
has these moments (Wensing, Kim & Slotine 2017): m >= 0, an inertia about the centre
of mass that is positive semidefinite and satisfies the triangle inequalities.  pi is
linear in J.  The friction, armature and Coulomb levels are >= 0, the offsets free.

The program minimizes D + B + Q:
- D = ||W (P pi - beta_hat)||^2, the estimate's Mahalanobis distance under its full
  (sandwich) covariance C = (W^T W)^-1 (P: base.project): correlated base parameters
  move together as the data allow;
- B = (2 / tolerance^2) sum_i d(J_i || J0_i), the URDF as a prior: the log-det (Bregman)
  divergence between pseudo-inertias (Lee & Park 2019)
      d(J || J0) = -log det(J0^-1 J) + tr(J0^-1 J) - 4,
  invariant to the link's frame and units.  Near J0 it is half the squared relative
  deviation along J0's principal directions (d = eps^2 / 2 for one eigenvalue scaled by
  1 + eps), so the factor 2 / tolerance^2 makes a deviation of `tolerance` cost 1: one
  standard error of the data, as in D;
- Q = sum_k ((pi_k - pi_urdf_k) / (tolerance * scale_k))^2 over the friction and the
  extra joint terms (the URDF's friction, 0 for the terms it has none of; prior_scales:
  the URDF's value or the data's scale): costs 1 at a deviation of `tolerance`, too.
One weight w = 1 / tolerance^2 multiplies the whole prior, so a tighter tolerance never
moves the model further from the URDF as a whole: with R = tolerance^2 (B + Q) (twice the
links' divergences plus the joint terms' squared relative deviations), the optima x1, x2
at w1 < w2 satisfy D1 + w1 R1 <= D2 + w1 R2 and D2 + w2 R2 <= D1 + w2 R1, hence
(w2 - w1)(R2 - R1) <= 0.  Link by link it holds unless links trade against each other
through the data (no scalar weight can promise more): a sweep on the UR5 and the two-link
arm finds no link moving away, on the Panda two links by at most 1e-4 in divergence.

A URDF link whose J0 is singular (no mass, a point mass, no inertia) or not positive
semidefinite has J0's eigenvalues lifted, in the metric of a reference body (a solid ball
of the robot's median link mass and size about the joint frame): a link without mass to
SINGULAR_FLOOR = 1, so its prior is the reference body, a typical link of the robot (the
divergence from a point is infinite, and from a small body it grows steeply: a 1 % body
held the two-link arm's data-determined base parameters 38 standard errors off); a link
with mass to CONDITION_FLOOR of its largest eigenvalue (the URDF's body, made regular;
every real link of the example robots is left as it is).

Scaling: each link's variable is X_i = C_i^-1 J_i C_i^-T with C_i C_i^T = J0_i (the
divergence is -log det X_i + tr X_i - 4: the URDF at X_i = 1, whatever the link's size
and units), each joint term's is its deviation relative to scale_k, and D is whitened
(each base parameter in units of its standard error).
"""
from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import cvxpy as cp
import numpy as np
import scipy.linalg
import scipy.stats
from lxml import etree

from .base_parameters import BaseParameters
from .consistent_errors import consistent_covariance
from .joint_terms import JointTerms
from .layout import ParameterLayout
from .mass_bounds import MassBounds
from .urdf import Robot, UrdfError, body_inertial, check_inertia, inertia_matrix, parse_urdf

# the default relative tolerance of the URDF's values (--urdf-tolerance):
# docs/design/robots.md explains the choice
DEFAULT_URDF_TOLERANCE = 0.3
CONFIDENCE = 0.95        # of the region the summary compares D with
# relative standard deviation added to each base parameter's: no estimate is taken as
# more precise than this (a noise-free log's would make the program needlessly stiff)
COVARIANCE_FLOOR = 1e-4
# a singular URDF pseudo-inertia's eigenvalues are lifted to this fraction of a reference
# body's (a link without mass: the reference body itself), or of its own largest (a link
# with mass; the Panda's go down to 3e-5 of it): module description
SINGULAR_FLOOR = 1.0
CONDITION_FLOOR = 1e-8
# Clarabel's settings, tried in turn until one reaches its tolerances (gap and feasibility
# 1e-8, never loosened): the defaults; then the linear systems refined to rounding; then
# more equilibration passes. On a noise-free estimate (weights up to 1e12) the defaults
# stop "almost solved" for about 3 % of last-bit perturbations of the same estimate, each
# alternative for 3-4 %, never all three together (200 perturbations of the offset and
# asymmetric Coulomb test case): docs/design/robots.md.
SOLVER_ATTEMPTS: tuple[dict[str, float], ...] = (
    {},
    {"iterative_refinement_reltol": 1e-15, "iterative_refinement_abstol": 1e-15},
    {"equilibrate_max_iter": 50},
)


class ProjectionError(RuntimeError):
    """The convex program of the consistent parameters has no accurate solution."""


@dataclass
class Projection:
    """The consistent parameters, the objective's parts at the optimum and the solver's
    report."""

    pi: np.ndarray          # consistent parameters (12 n standard, then the joint terms)
    distance: float         # D: Mahalanobis distance^2 of beta(pi) from the estimate
    bound: float            # chi2_r(CONFIDENCE): D beyond it leaves the confidence region
    divergence: float       # B: the links' prior, 2 / tolerance^2 * sum of divergences
    terms_prior: float      # Q: the friction's and joint terms' prior
    link_divergence: np.ndarray  # (n,) d(J_i || J0_i) per link (0: not identified)
    tolerance: float        # the stated relative tolerance of the URDF's values
    status: str             # the solver's status (cvxpy's: "optimal")
    gap: float              # |primal - dual objective| / max(1, |primal|) (NaN: unknown)
    base_std: np.ndarray    # (r,) standard errors of the consistent base parameters
    settings: dict[str, float]  # the solver's settings that reached it (SOLVER_ATTEMPTS)
    seconds: float          # building and solving the program
    error: float            # score(beta(pi)): the training-log error (0 without a score)

    @property
    def objective(self) -> float:
        """D + B + Q at the optimum."""
        return self.distance + self.divergence + self.terms_prior

    def as_json(self) -> dict:
        """summary.json's record of the projection."""
        return {"urdf_tolerance": self.tolerance, "solver": "clarabel",
                "solver_status": self.status, "duality_gap": _finite(self.gap),
                "solver_settings": self.settings,
                "objective": self.objective, "mahalanobis_distance2": self.distance,
                "confidence_bound": self.bound, "urdf_divergence": self.divergence,
                "joint_terms_prior": self.terms_prior,
                "link_divergence": [_finite(d) for d in self.link_divergence],
                "training_error": self.error}


def _finite(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None


def pseudo_inertia(link: np.ndarray) -> np.ndarray:
    """The pseudo-inertia J (4 x 4) of a link's 10 parameters (m, m c, I_o)."""
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


def divergence(J: np.ndarray, J0: np.ndarray) -> float:
    """d(J || J0) = -log det(J0^-1 J) + tr(J0^-1 J) - 4 (J0 positive definite; inf if J is
    not)."""
    X = np.linalg.solve(J0, J)
    sign, logdet = np.linalg.slogdet(X)
    return float(np.trace(X) - logdet - 4) if sign > 0 else float("inf")


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
    friction.  (The projection's prior uses the friction's and joint terms' scales; the
    links' are the divergence's, for reading a link's values.)"""
    nominal = np.asarray(nominal, float)
    data_scale = np.asarray(data_scale, float)
    physical = np.full(len(nominal), np.nan)  # 12 n, and the extra joint terms
    layout = ParameterLayout(n)
    for i in range(n):
        link = nominal[layout.link(i)]
        mass = link[0]
        trace = link[4] + link[6] + link[9]
        if mass > 0 and trace > 0:
            size = np.sqrt(trace / (2 * mass))
            physical[layout.link(i)] = [mass, *[mass * size] * 3, *[mass * size ** 2] * 6]
    fallback = np.where(np.isfinite(data_scale) & (data_scale > 0), data_scale, np.nan)
    physical = np.where(np.isnan(physical), fallback, physical)
    scale = np.fmax(np.abs(nominal), physical)
    return np.where(np.isfinite(scale) & (scale > 0), scale, 1.0)


def reference_body(nominal: np.ndarray, n: int) -> np.ndarray:
    """The pseudo-inertia (4 x 4, diagonal) of a solid ball of the robot's median URDF
    link mass and size (sqrt(tr I_o / 2m) over the links with mass; 1 kg and 0.1 m
    without any) centred on the joint frame: the metric of regularized_prior."""
    masses, sizes = [], []
    layout = ParameterLayout(n)
    for i in range(n):
        link = nominal[layout.link(i)]
        mass, trace = link[0], link[4] + link[6] + link[9]
        if mass > 0 and trace > 0:
            masses.append(mass)
            sizes.append(np.sqrt(trace / (2 * mass)))
    mass = float(np.median(masses)) if masses else 1.0
    size = float(np.median(sizes)) if sizes else 0.1
    return np.diag([mass * size ** 2 / 5] * 3 + [mass])  # Sigma = m r^2 / 5 of a ball


def regularized_prior(J0: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """J0 positive definite: its eigenvalues in the reference body's metric (R^-1/2 J0
    R^-1/2, R diagonal) lifted to at least SINGULAR_FLOOR for a link without mass in the
    URDF (the reference body itself for J0 = 0), to CONDITION_FLOOR of the largest for one
    with mass (a point mass, a rod or rounding: the URDF's body, made regular).
    Unchanged where it already is that far from singular (every link of the example
    robots)."""
    root = np.sqrt(np.diag(reference))
    values, vectors = np.linalg.eigh(J0 / np.outer(root, root))
    floor = CONDITION_FLOOR * values[-1] if J0[3, 3] > 0 else SINGULAR_FLOOR
    if values[0] >= floor:
        return J0
    lifted = (vectors * np.maximum(values, floor)) @ vectors.T
    return 0.5 * (lifted + lifted.T) * np.outer(root, root)


def consistent_parameters(robot: Robot, base: BaseParameters, beta: np.ndarray,
                          covariance: np.ndarray, data_scale: np.ndarray | None = None,
                          tolerance: float = DEFAULT_URDF_TOLERANCE,
                          score: Callable[[np.ndarray], float] | None = None,
                          terms: JointTerms | None = None,
                          bounds: MassBounds | None = None) -> Projection:
    """Standard parameters pi (12 n, then terms.count(n) joint terms) that are physically
    consistent and minimize the estimate's Mahalanobis distance (beta: the base
    estimate, covariance (r, r) its covariance) plus the URDF's prior at the relative
    `tolerance` (> 0): the convex program of the module's description.  data_scale (as
    long as pi): see prior_scales (None: the URDF's values alone).  score(beta), if
    given, is the training-log prediction error of base parameters beta, reported for
    the result.  Only the links and friction among the identified (base and dependent)
    columns move; the others keep the URDF's values.

    terms (harness.robot.joint_terms): the extra joint terms after the 12 n standard
    parameters: the offsets free, the armature and the Coulomb levels >= 0, their prior 0
    (the URDF has none) at the data's scale.  bounds (harness.robot.mass_bounds): link
    mass ranges and the chain's total mass, as linear constraints; a range on a link the
    log does not identify must hold its URDF mass.

    ProjectionError if the solver does not report an optimal solution."""
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise ValueError(f"the URDF tolerance must be a finite number > 0, not {tolerance!r}")
    started = time.perf_counter()
    n = robot.n
    terms = terms or JointTerms()
    extra = terms.count(n)
    layout = ParameterLayout(n, len(terms.kinds))
    size = layout.size
    nominal = np.concatenate([robot.parameters(), np.zeros(extra)])
    free = np.union1d(base.base, base.dependent)
    links = sorted({int(k) // layout.link_size for k in free if k < layout.link_end})
    joint = np.array([k for k in free if k >= layout.link_end], dtype=int)  # friction, terms
    friction = np.ones(layout.friction_size * n, bool)  # viscous and Coulomb: >= 0
    nonnegative = np.concatenate([friction, terms.nonnegative(n)])[joint - layout.link_end]
    if data_scale is None:
        data_scale = np.full(size, np.nan)
    scale = prior_scales(nominal, n, data_scale)[joint]
    reference = reference_body(nominal, n)
    priors = [regularized_prior(pseudo_inertia(nominal[layout.link(i)]), reference)
              for i in links]
    factors = [np.linalg.cholesky(J0) for J0 in priors]

    # pi = fixed + A z, z = (vec X_1, ..., vec X_L, u): X_i = C_i^-1 J_i C_i^-T, u the joint
    # terms' deviations relative to their scales
    fixed = nominal.copy()
    A = np.zeros((size, 16 * len(links) + len(joint)))
    unit = np.eye(16).reshape(16, 4, 4).transpose(0, 2, 1)  # vec's column-major order
    for j, (i, C) in enumerate(zip(links, factors)):
        fixed[layout.link(i)] = 0.0
        A[layout.link(i), 16 * j:16 * j + 16] = link_of_pseudo_inertia(C @ unit @ C.T).T
    A[joint, 16 * len(links) + np.arange(len(joint))] = scale
    whiten = _whitening(beta, covariance)
    projector = base.project(np.eye(size)).T  # (r, size): beta = P pi
    M = whiten @ projector @ A
    b = whiten @ (beta - projector @ fixed)

    X = [cp.Variable((4, 4), PSD=True) for _ in links]
    u = cp.Variable(len(joint))
    z = cp.hstack([*(cp.vec(x, order="F") for x in X), u])
    weight = 1.0 / tolerance ** 2
    data = cp.sum_squares(M @ z - b)
    links_prior = 2 * weight * sum((cp.trace(x) - cp.log_det(x) - 4 for x in X),
                                   start=cp.Constant(0.0))
    terms_prior = weight * cp.sum_squares(u)
    lower = -nominal[joint[nonnegative]] / scale[nonnegative]  # pi_k >= 0
    constraints = [u[np.flatnonzero(nonnegative)] >= lower] if np.any(nonnegative) else []
    constraints += _bound_constraints(robot, bounds, fixed, A, z)
    problem = cp.Problem(cp.Minimize(data + links_prior + terms_prior), constraints)
    solution, settings = _solve(problem, z, bounds is not None and bounds.any)
    pi = fixed + A @ z.value
    # the solver meets its inequalities to its tolerance: a level or mass at its bound 0
    # can end at -1e-15, which a URDF reader (ours too) refuses as negative
    pi[joint[nonnegative]] = np.maximum(pi[joint[nonnegative]], 0.0)
    pi[layout.masses] = np.maximum(pi[layout.masses], 0.0)
    # the joint terms held at their bounds do not move with the estimate
    held = np.zeros(len(joint), dtype=bool)
    values = np.asarray(u.value)
    if np.any(nonnegative):
        at = np.flatnonzero(nonnegative)
        held[at] = values[at] <= lower + 1e-7 * np.maximum(1.0, np.abs(lower))
    base_covariance = consistent_covariance([np.asarray(x.value) for x in X], ~held, weight,
                                            M, whiten, A, projector, covariance)
    distance = float(np.sum((whiten @ (projector @ pi - beta)) ** 2))
    per_link = np.zeros(n)
    for i, J0 in zip(links, priors):
        per_link[i] = divergence(pseudo_inertia(pi[layout.link(i)]), J0)
    deviation = (pi[joint] - nominal[joint]) / scale
    return Projection(
        pi, distance, float(scipy.stats.chi2.ppf(CONFIDENCE, len(beta))),
        2 * weight * float(per_link.sum()), weight * float(deviation @ deviation), per_link,
        tolerance, str(problem.status), _gap(solution),
        np.sqrt(np.maximum(np.diag(base_covariance), 0.0)), settings,
        time.perf_counter() - started, float(score(projector @ pi)) if score is not None else 0.0)


def _bound_constraints(robot: Robot, bounds: MassBounds | None, fixed: np.ndarray,
                       A: np.ndarray, z: cp.Expression) -> list:
    """The mass bounds and the centres of mass's boxes as constraints on z (each link's
    mass and first moment are fixed + A z at their indices: linear; a centre of mass c
    inside [low, high] is m low <= m c <= m high); ProjectionError for a range that a
    link the log does not identify (its mass fixed at the URDF's) cannot meet. A box
    binds only the links the log identifies."""
    if bounds is None or not bounds.any:
        return []
    layout = ParameterLayout(robot.n)
    mass = [fixed[layout.mass(i)] + A[layout.mass(i)] @ z for i in range(robot.n)]
    constraints = []
    for i, (low, high) in bounds.ranges.items():
        if not A[layout.mass(i)].any() and not low <= fixed[layout.mass(i)] <= high:
            raise ProjectionError(
                f"--mass-range {robot.joints[i].child_link}={low:g}:{high:g}: the log does "
                f"not identify this link (--unknown), so its mass stays the URDF's "
                f"{fixed[layout.mass(i)]:g} kg, outside the range")
        constraints += [mass[i] >= low, mass[i] <= high]
    if bounds.total is not None:
        constraints.append(cp.sum(cp.hstack(mass)) == bounds.total)
    for i, (corner_low, corner_high) in bounds.com_boxes.items():
        rows = layout.first_moment(i)
        if A[layout.mass(i)].any() or A[rows].any():
            moment = fixed[rows] + A[rows] @ z
            constraints += [moment >= corner_low * mass[i], moment <= corner_high * mass[i]]
    return constraints


def _solve(problem: cp.Problem, z: cp.Expression, bounded: bool = False):
    """Clarabel's own solution of the problem (it reports the dual objective), its values
    unpacked into the variables, with the first of SOLVER_ATTEMPTS that ends optimal;
    ProjectionError if none does (``bounded``: the program holds mass bounds, which may
    leave no solution)."""
    conic, chain, inverse = problem.get_problem_data(cp.CLARABEL, solver_opts={})
    ended = []
    for settings in SOLVER_ATTEMPTS:
        try:
            solution = chain.solve_via_data(problem, conic, solver_opts=dict(settings))
            with warnings.catch_warnings():  # an inaccurate solution is our error, below
                warnings.filterwarnings("ignore", "Solution may be inaccurate", UserWarning)
                problem.unpack_results(solution, chain, inverse)
        except cp.error.SolverError:  # a numerical failure: the next settings may pass
            ended.append("failed")
            continue
        if problem.status == cp.OPTIMAL and z.value is not None:
            return solution, settings
        ended.append(f"status {problem.status!r}")
    why = ("the estimate's covariance or the URDF's values may span too many orders of "
           "magnitude")
    if bounded:
        why = ("no physically consistent model may meet the bounds (--mass-range, "
               "--total-mass, --com-in-geometry) together, or " + why)
    raise ProjectionError(
        f"the consistent parameters: the solver Clarabel ended {', '.join(ended)} with its "
        f"{len(SOLVER_ATTEMPTS)} settings, never optimal ({why}): no model is written")


def _gap(solution) -> float:
    """The relative duality gap of Clarabel's solution (NaN if it does not report it)."""
    primal = getattr(solution, "obj_val", None)
    dual = getattr(solution, "obj_val_dual", None)
    if primal is None or dual is None:
        return float("nan")
    return abs(primal - dual) / max(1.0, abs(primal))


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
    layout = ParameterLayout(robot.n)
    for i, joint in enumerate(robot.joints):
        mass, com, inertia = body_inertial(pi[layout.link(i)])
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
        etree.SubElement(element, "dynamics", damping=f"{pi[layout.viscous(i)]:.12g}",
                         friction=f"{pi[layout.coulomb(i)]:.12g}")
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
