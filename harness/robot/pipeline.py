"""Offline identification of a serial robot from a log of joint positions and torques.

    python -m harness identify DATA.csv --robot ROBOT.urdf --out DIR

DATA.csv (or a Parquet or MATLAB file) has columns t, q1..qn (rad, or m for prismatic joints),
u1..un (N.m or N); other names map with --columns q1=shoulder_pos etc., other units
with --time-unit, --angle-unit, --length-unit and --torque-gains (currents times the
drives' gains; harness.robot.log_units); a MATLAB file or a log without a time column
with --sample-rate.  Steps:
1. velocities: Savitzky-Golay (zero-phase, the default: the velocities written over
   a window each joint chooses, the regression's signals over the longest of them,
   accelerations and torques filtered alike, harness.robot.smoothing) or a causal, model-free
   observer per joint, the observer FMU's default estimator through the C core
   (observer_velocities);
2. the base regressor of the URDF's model (C core): at the smoothed signals (sg) or in
   momentum form through a causal filter, with no acceleration (observer,
   harness.robot.filtered_regression); the joints' equations weighted by their residual
   RMS, least squares with standard errors (harness.model.fit, the model files' too);
3. physically consistent link parameters near the URDF's (harness.robot.consistency),
   written as DIR/identified.urdf with the joints' viscous and Coulomb friction.
Extra joint terms (--joint-terms, --smooth-coulomb: offsets, armature, asymmetric or
smooth Coulomb friction, harness.robot.joint_terms) are extra regressor columns built
here; what a URDF cannot hold goes to DIR/joint_terms.csv.
"""
from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..model.fit import Fit, expanded
from ..model.fit import fit as least_squares
from ..model.friction_rows import joint_friction_rows
from .assessment import Choice, choose_model, prediction_error
from .base_parameters import BaseParameters, base_parameters
from .consistency import (
    DEFAULT_URDF_TOLERANCE,
    Projection,
    consistent_parameters,
)
from .filtered_regression import filtered_regression, low_pass
from .joint_log import JointLog, LogError
from .joint_terms import (
    COULOMB_NEGATIVE,
    COULOMB_POSITIVE,
    JointTerms,
    check_directions,
)
from .layout import ParameterLayout
from .mass_bounds import MassBounds
from .model_class import TermsChoice, choose_joint_terms
from .native import core_defaults
from .smoothing import (
    SHORTEST_REGRESSION_WINDOW,
    adaptive_velocities,
    observer_velocities,
    regression_window,
    savitzky_golay,
    smooth_column,
)
from .urdf import Robot

# a joint keeping fewer of its equations than this share is an error (its friction cannot
# be identified), fewer than FEW_ROWS a warning
TOO_FEW_ROWS, FEW_ROWS = 0.01, 0.1


@dataclass
class Identification:
    base: BaseParameters
    fit: Fit
    pi: np.ndarray                # consistent parameters (12 n, then the joint terms')
    velocity: np.ndarray          # (N, n)
    used: np.ndarray              # indices of the samples used in the regression
    velocity_window: np.ndarray | None = None  # per joint [s] ("sg": the velocity's window)
    window: float = SHORTEST_REGRESSION_WINDOW  # the regression's Savitzky-Golay window [s]
    projection: Projection | None = None  # the consistent parameters and their distance
    choice: Choice | None = None          # the training-log scores, what is written, warnings
    passive: list[str] = field(default_factory=list)  # joints whose torque is 0 throughout
    terms: JointTerms = field(default_factory=JointTerms)  # the extra joint terms
    terms_choice: TermsChoice | None = None  # how they were chosen (choose_terms)
    unmeasured: list[str] = field(default_factory=list)  # joints whose torque the log lacks
    mass_bounds: MassBounds | None = None  # the bounds the consistent model was held to

    @property
    def warnings(self) -> list[str]:
        return [] if self.choice is None else self.choice.warnings

    @property
    def urdf_kept(self) -> bool:
        """True if identified.urdf keeps the input URDF's values (assessment.py)."""
        return self.choice is not None and self.choice.written == "urdf"

    def standard(self, n: int) -> np.ndarray:
        """The 12 n parameters identified.urdf holds: with asymmetric Coulomb friction
        (unless the URDF's values are kept), each joint's Coulomb friction is the mean
        of its two levels."""
        layout = ParameterLayout(n)
        pi = self.pi[layout.standard].copy()
        if self.terms.asymmetric_coulomb and not self.urdf_kept:
            levels = self.term_values(n)
            kinds = list(self.terms.kinds)
            pi[layout.coulomb_levels] = 0.5 * (levels[:, kinds.index(COULOMB_POSITIVE)] +
                                               levels[:, kinds.index(COULOMB_NEGATIVE)])
        return pi

    def term_values(self, n: int) -> np.ndarray:
        """(n, k): each joint's extra terms (terms.kinds' order)."""
        return ParameterLayout(n, len(self.terms.kinds)).split(self.pi)[2]

    def term_std_errors(self, n: int) -> np.ndarray:
        """(k n,): each extra term's standard error where the term is a base parameter
        by itself (no other parameter folded into it), NaN where it is not identified
        alone."""
        out = np.full(self.terms.count(n), np.nan)
        start = ParameterLayout(n).standard_size  # the terms' first column
        for row, column in enumerate(self.base.base):
            if column >= start and not np.any(np.abs(self.base.K[row]) > 1e-9):
                out[column - start] = self.fit.std_error[row]
        return out


@dataclass
class Rows:
    """The samples identify regresses: the core model's regressor (rows, n, 12 n) and the
    torques (rows, n) at the samples `used`, each joint's speed there, the joint equations
    that enter (friction_rows), the rows over which residuals may be correlated, and the
    regressor of a model class (`extend`: the core's with its extra joint terms)."""

    used: np.ndarray
    core: np.ndarray
    torque: np.ndarray
    speed: np.ndarray
    mask: np.ndarray
    correlation: int
    extend: Callable[[JointTerms], np.ndarray]


def identify_robot(robot: Robot, log: JointLog, unknown: str = "all", method: str = "sg",
                   window: float | None = None, tau: float = 0.02, max_samples: int = 20000,
                   skip: float = 0.5, min_speed: float | None = None,
                   urdf_tolerance: float = DEFAULT_URDF_TOLERANCE,
                   terms: JointTerms | None = None, choose_terms: str | None = None,
                   mass_bounds: MassBounds | None = None) -> Identification:
    """Identify the unknown parameters ("all" or "payload") from the log.

    window: the regression's Savitzky-Golay window [s] (None: "sg" takes the joints'
    velocity windows' longest, smoothing.regression_window; "observer" 0.05 s).
    The first `skip` seconds (observer convergence, filter edges) and the last window
    are not used; at most max_samples evenly spaced samples enter the regression.
    Joint i's equation is left out near its velocity reversals and where
    |q_i'| < min_speed (rad/s or m/s, None: the core's default; see friction_rows).
    method "observer": tau is the time constant of the regression's causal filter (two
    first-order stages).  urdf_tolerance: how far (relative) the URDF's values are
    trusted where the data leave the consistent parameters open (consistency.py); the
    URDF's values are kept if the identified model predicts the training log worse
    (assessment.py).  A joint whose torque is 0 throughout is passive: its equation
    (torque = 0) constrains the parameters like any other.  terms: the extra joint terms
    (harness.robot.joint_terms; None: the core's model alone), identified with the rest;
    choose_terms: the terms chosen from the log instead (harness.robot.model_class):
    "required" (LogSignalsError if no class can be compared) or "default" (then the
    core's model alone, said in the choice's note); mass_bounds: the links' mass ranges
    and total mass the consistent model must meet (harness.robot.mass_bounds);
    the URDF's prediction is the core's model with the URDF's values."""
    if log.q.shape[1] != robot.n:
        raise LogError(f"the log has {log.q.shape[1]} joints, the robot {robot.n}")
    if method not in ("sg", "observer"):
        raise ValueError(f"unknown method {method!r}: 'sg' or 'observer'")
    velocity_window = None
    if method == "sg":
        velocity, velocity_window = adaptive_velocities(log.q, log.step)
        if window is None:
            window = regression_window(velocity_window)
    elif window is None:
        window = SHORTEST_REGRESSION_WINDOW
    # whole samples, rounded: a step of 1 ms read as 1.0000000000000002 ms (a log in ms)
    # must not move the first sample used
    first, last = round(skip / log.step), len(log.t) - round(window / log.step) - 1
    if last - first < 10:
        raise LogError(f"the log ({log.t[-1] - log.t[0]:g} s) is too short")
    stride = max(1, (last - first) // max_samples)
    used = np.arange(first, last, stride)
    body = robot.rigid_body()
    if method == "observer":
        bound = 1.5 * np.array([np.abs(smooth_column(log, log.q[:, i], max(window, 0.05), deriv=2)
                                       ).max() for i in range(robot.n)]) + 1e-3
        velocity = observer_velocities(log, bound)
    rows = regression_rows(robot, body, log, method, window, tau, used, velocity,
                           core_defaults().min_speed if min_speed is None else min_speed)
    types = robot.arrays()["types"]

    bases: dict[JointTerms, BaseParameters] = {}  # the chosen class's: computed once

    def base_for(model: JointTerms) -> BaseParameters:
        if model not in bases:
            bases[model] = base_parameters(body, types, robot.joint_names, unknown, terms=model)
        return bases[model]
    choice = None
    if choose_terms is not None:
        choice = choose_joint_terms(rows, base_for, robot.parameters(), robot.joint_names,
                                    required=choose_terms == "required")
        terms = choice.terms
    terms = terms or JointTerms()
    one_way = check_directions(terms, rows.speed, rows.mask, robot.joint_names)
    if one_way is not None:
        raise LogError(one_way)
    base = base_for(terms)
    Y = rows.extend(terms)
    result = _identified(robot, rows, base, Y, terms, urdf_tolerance, mass_bounds)
    passive = [name for i, name in enumerate(robot.joint_names)
               if not np.any(log.u[:, i]) and i not in log.unmeasured]
    return Identification(result[0], result[1], result[2], velocity, used, velocity_window,
                          window, result[3], result[4], passive, terms, choice,
                          [robot.joint_names[i] for i in log.unmeasured], mass_bounds)


def regression_rows(robot: Robot, body, log: JointLog, method: str, window: float,
                    tau: float, used: np.ndarray, velocity: np.ndarray, min_speed: float
                    ) -> Rows:
    """The Rows of `method` ("sg": the Savitzky-Golay signals of `window` s; "observer":
    the momentum form through the causal filter of time constant tau, from the observer's
    `velocity`) at the samples `used`, each joint's equation left out near its reversals
    and below min_speed (friction_rows); body: the robot's C model (robot.rigid_body())."""
    # each joint's velocity over the whole log is needed only for its friction rows
    # (friction_rows): one column at a time, the regression's signals at `used` only
    if method == "sg":
        q, qd, qdd, u = savitzky_golay(log, window, at=used)
        core, torque = body.regressor(q, qd, qdd), u
        margin, slow_margin, memory = window, 0.0, window

        def extend(model: JointTerms) -> np.ndarray:
            return model.extend(core, qd, qdd)

        def joint_speed(i: int) -> np.ndarray:
            return smooth_column(log, log.q[:, i], window, deriv=1)
    else:
        core, torque = filtered_regression(body, log.q, velocity, log.u, log.step, tau, used)
        margin = slow_margin = max(window, 4 * tau)
        memory = max(window, tau)

        def extend(model: JointTerms) -> np.ndarray:
            return model.extend_filtered(core, velocity, log.step, tau, used)

        def joint_speed(i: int) -> np.ndarray:
            return low_pass(velocity[:, i], log.step, tau)
    stride = int(used[1] - used[0]) if len(used) > 1 else 1
    correlation = max(1, int(np.ceil(2 * memory / (stride * log.step) - 1e-9)))
    mask, speed = np.empty((len(used), robot.n), dtype=bool), np.empty((len(used), robot.n))
    for i in range(robot.n):
        x = joint_speed(i)
        mask[:, i] = joint_friction_rows(x, log.step, margin, min_speed, slow_margin, used)
        speed[:, i] = x[used]
    measured = log.measured
    check_friction_rows(mask[:, measured], speed[:, measured],
                        [name for name, m in zip(robot.joint_names, measured) if m], min_speed)
    mask[:, ~measured] = False  # its equation left out; its dynamics stay in the others'
    return Rows(used, core, torque, speed, mask, correlation, extend)


def known_columns(n: int, base: BaseParameters) -> np.ndarray:
    """The standard parameters taken as the URDF's (neither base nor folded into one)."""
    layout = ParameterLayout(n)
    return np.setdiff1d(layout.indices(layout.standard), np.union1d(base.base, base.dependent))


def _identified(robot: Robot, rows: Rows, base: BaseParameters, Y: np.ndarray,
                terms: JointTerms, urdf_tolerance: float, mass_bounds: MassBounds | None):
    """The least squares of the base parameters, the consistent parameters near the URDF
    and the choice of what identified.urdf holds."""
    names, torque, mask = robot.joint_names, rows.torque, rows.mask
    # the known part of the model (all but the unknown columns) moves to the left side
    known = known_columns(robot.n, base)
    nominal = robot.parameters()
    known_torque = Y[:, :, known] @ nominal[known]
    # the ridge of the one least squares pulls a weakly excited base parameter toward the
    # URDF's value
    nominal_beta = base.project(np.concatenate([nominal, np.zeros(terms.count(robot.n))]))
    # the base regressor over the kept equations only (a copy: fancy indexing), for the
    # fit, the scores and the estimate's prediction alike
    Yb = base.regressor(Y)
    Yb *= mask[:, :, None]
    # a base parameter that no kept equation holds (an unmeasured joint's friction) keeps
    # the URDF's value, standard error 0, instead of a singular fit
    held = ~np.any(Yb, axis=(0, 1))
    fit = least_squares(Yb[:, :, ~held], torque - known_torque, nominal_beta[~held],
                        batch=rows.correlation, mask=mask)
    if held.any():
        fit = expanded(fit, ~held, np.zeros(len(held)), nominal_beta)
    # each parameter's value that alone would explain the torques (prior_scales)
    measured = torque * mask
    with np.errstate(divide="ignore"):
        data_scale = (np.linalg.norm(measured) /
                      np.sqrt(np.einsum("kij,kij,ki->j", Y, Y, mask.astype(float))))
    left, total = measured - known_torque * mask, float(np.linalg.norm(measured))

    def score(beta: np.ndarray) -> float:
        """The pooled training-log error of base parameters beta (prediction_error)."""
        return float(np.linalg.norm(left - Yb @ beta)) / total if total > 0 else 0.0
    projection = consistent_parameters(robot, base, fit.theta, fit.covariance, data_scale,
                                       urdf_tolerance, score, terms, mass_bounds)
    predictions = {
        "urdf": prediction_error(rows.core @ nominal, torque, mask, names),
        # the left-out equations' predictions do not count: Yb is 0 there
        "estimate": prediction_error(known_torque + Yb @ fit.theta, torque, mask, names),
        "consistent": prediction_error(Y @ projection.pi, torque, mask, names)}
    missing = tuple(name for name, present in (("offset", terms.offset),
                                               ("armature", terms.armature)) if not present)
    choice = choose_model(predictions, projection.pi,
                          np.concatenate([nominal, np.zeros(terms.count(robot.n))]),
                          [joint.child_link for joint in robot.joints], missing)
    return base, fit, choice.pi, projection, choice


def check_friction_rows(mask: np.ndarray, velocity: np.ndarray, names: list[str],
                        min_speed: float) -> None:
    """LogError naming each joint that keeps fewer than TOO_FEW_ROWS of its equations
    (mask (N, n) from friction_rows; velocity (N, n) at the same samples): its friction
    cannot be identified; a warning below FEW_ROWS.  The remedy: a smaller --min-speed
    or a log in which the joint moves faster."""
    kept = mask.mean(axis=0)
    messages = []
    for i in np.flatnonzero(kept < FEW_ROWS):
        speed = np.abs(velocity[:, i])
        messages.append(
            f"joint {names[i]!r} keeps {100 * kept[i]:.1f} % of its equations: |q'| >= "
            f"min_speed {min_speed:g} in {100 * np.mean(speed >= min_speed):.1f} % of the "
            f"samples (median |q'| {np.median(speed):.3g}, largest {speed.max():.3g}); lower "
            f"--min-speed (e.g. to {0.5 * np.median(speed):.2g}) or log a trajectory that "
            f"moves this joint faster")
    if np.any(kept < TOO_FEW_ROWS):
        raise LogError("too few joint equations left to identify the friction: " +
                       "; ".join(messages))
    for message in messages:
        warnings.warn(message, stacklevel=3)
