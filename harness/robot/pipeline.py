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

import csv
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.signal import savgol_filter

from ..json_files import write_json
from ..log_signals import Column, LogSignalsError, header_of, read_signals
from ..model.fit import Fit, expanded
from ..model.fit import fit as least_squares
from ..model.friction_rows import joint_friction_rows
from .assessment import Choice, choose_model, prediction_error
from .base_parameters import BaseParameters, base_parameters
from .consistency import (
    DEFAULT_URDF_TOLERANCE,
    Projection,
    consistent_parameters,
    write_identified_urdf,
)
from .filtered_regression import filtered_regression, low_pass
from .joint_terms import (
    COULOMB_NEGATIVE,
    COULOMB_POSITIVE,
    SIDECAR_NAME,
    JointTerms,
    check_directions,
    write_sidecar,
)
from .layout import ParameterLayout
from .log_units import LogUnits
from .model_class import TermsChoice, choose_joint_terms
from .native import core_defaults
from .smoothing import SHORTEST_REGRESSION_WINDOW, adaptive_velocities, regression_window
from .urdf import Robot

# a joint keeping fewer of its equations than this share is an error (its friction cannot
# be identified), fewer than FEW_ROWS a warning
TOO_FEW_ROWS, FEW_ROWS = 0.01, 0.1
# what write_results writes into the output folder
WRITE_ROWS = 1 << 16  # rows of velocities.csv formatted at a time
PLOT_BINS = 4000      # stretches of a long log's velocity plot (plot_samples)
OUTPUT_NAMES = ("velocities.csv", "parameters.csv", "identified.urdf", "summary.json",
                "velocities.png", SIDECAR_NAME)


#: A joint log that cannot be used; the message names the file and line or column.
LogError = LogSignalsError


@dataclass
class JointLog:
    t: np.ndarray   # (N,)
    q: np.ndarray   # (N, n)
    u: np.ndarray   # (N, n); 0 for a joint whose torque the log does not hold
    resampled: str | None = None  # what was done to a log whose clock jitters (None: nothing)
    unmeasured: tuple[int, ...] = ()  # those joints (0-based)

    @property
    def step(self) -> float:
        """The sampling step: the mean step (robust to the rounding of epoch stamps)."""
        return float((self.t[-1] - self.t[0]) / (len(self.t) - 1))

    @property
    def measured(self) -> np.ndarray:
        """(n,) False for the joints whose torque the log does not hold."""
        out = np.ones(self.q.shape[1], dtype=bool)
        out[list(self.unmeasured)] = False
        return out


def read_log(path: str | Path, n: int, mapping: dict[str, str] | None = None,
             relative_tolerance: float = 0.01, units: LogUnits | None = None,
             sample_rate: float | None = None, unmeasured: Sequence[int] = ()) -> JointLog:
    """Columns t, q1..qn, u1..un (or the names or 1-based column numbers `mapping` gives
    them; a CSV file without a header row has them in that order) of a CSV, Parquet or
    MATLAB log, read by the one log reader (harness.log_signals): a clock whose steps
    differ from the mean step by more than `relative_tolerance` is resampled onto even
    steps, a gap refused.  `units` (harness.robot.log_units) brings the columns to s, rad
    or m and N.m or N (None: they are in these units).  With a `sample_rate` [Hz] no time
    column is read: the samples are evenly spaced at it from t = 0.  The joints
    ``unmeasured`` (0-based) have no torque column (JointLog.unmeasured)."""
    path, mapping = Path(path), dict(mapping or {})
    measured = [i for i in range(n) if i not in set(unmeasured)]
    positions, torques = [f"q{i}" for i in range(1, n + 1)], [f"u{i + 1}" for i in measured]
    wanted = ([] if sample_rate is not None else ["t"]) + positions + torques
    if units is not None and len(units.position) != n:
        raise ValueError(f"units for {len(units.position)} joints, the robot has {n}")
    header, hint = header_of(path), f"; needed: {', '.join(wanted)}"
    if header is not None:
        if not header.present and not mapping:
            # no header row: the columns in the roles' order, t, q1..qn, u1..un
            if len(header) != len(wanted):
                raise LogError(f"{path}: no header row and {len(header)} columns; a robot of "
                               f"{n} joints needs {len(wanted)} ({', '.join(wanted)}) or "
                               "--columns with column numbers")
            mapping = {role: str(k + 1) for k, role in enumerate(wanted)}
        found = [k for k in header if k.startswith("q") and k[1:].isdigit()]
        if found and len(found) != n:
            hint += f"; the file has {len(found)} position columns but the robot has {n} joints"
        if len(found) > n and not mapping:
            raise LogError(f"{path}: {len(found)} position columns for a robot of {n} joints")

    def columns(roles: list[str]) -> list[Column]:
        return [Column(role, mapping.get(role, role)) for role in roles]
    signals = read_signals(
        path, None if sample_rate is not None else Column("t", mapping.get("t", "t")),
        columns(positions), columns(torques), sample_rate=sample_rate,
        time_factor=1.0 if units is None else units.time,
        factors=None if units is None else np.concatenate([units.position,
                                                           units.torque[measured]]),
        missing_hint=hint, tolerance=relative_tolerance,
        slow_step_hint=None if units is not None and units.time_unit is not None else
        "give --time-unit ms (--time-unit s confirms seconds)")
    u = np.zeros((len(signals.t), n))
    u[:, measured] = signals.inputs
    return JointLog(signals.t, signals.q, u, signals.resampled,
                    tuple(i for i in range(n) if i not in measured))


def _odd(count: int) -> int:
    return count if count % 2 else count + 1


def savitzky_golay(log: JointLog, window: float, order: int = 4,
                   at: np.ndarray | None = None):
    """(q, q', q'', u) smoothed by one zero-phase Savitzky-Golay filter of `window` s,
    at the samples `at` (None: every sample); a column at a time, so that a long log
    needs one column's work space, not four arrays of the log's length."""
    rows = slice(None) if at is None else at
    out = []
    for x, deriv in ((log.q, 0), (log.q, 1), (log.q, 2), (log.u, 0)):
        smooth = np.empty((len(x) if at is None else len(at), x.shape[1]))
        for i in range(x.shape[1]):
            smooth[:, i] = smooth_column(log, x[:, i], window, order, deriv)[rows]
        out.append(smooth)
    return tuple(out)


def smooth_column(log: JointLog, x: np.ndarray, window: float, order: int = 4,
            deriv: int = 0) -> np.ndarray:
    """One column x (N,) of the log through the Savitzky-Golay filter of `window` s."""
    length = _odd(max(order + 2, round(window / log.step)))
    if length > len(log.t):
        raise LogError(f"the Savitzky-Golay window ({length} samples) is longer than the log")
    return savgol_filter(x, length, order, deriv=deriv, delta=log.step)


def observer_velocities(log: JointLog, acceleration_bound: np.ndarray) -> np.ndarray:
    """Each joint's velocity by the observer FMU's default estimator without a model
    (harness.robot.native.observe_adaptive: the implicit super-twisting observer beside
    the noise-adaptive bank of linear observers, which estimates the encoder noise
    itself): causal, the estimate at a sample from the positions up to it."""
    from .native import observe_adaptive
    return observe_adaptive(log.q, log.step, acceleration_bound).velocity


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
                   terms: JointTerms | None = None, choose_terms: bool = False
                   ) -> Identification:
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
    choose_terms: the terms chosen from the log instead (harness.robot.model_class);
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
    if choose_terms:
        choice = choose_joint_terms(rows, base_for, robot.parameters(), robot.joint_names)
        terms = choice.terms
    terms = terms or JointTerms()
    one_way = check_directions(terms, rows.speed, rows.mask, robot.joint_names)
    if one_way is not None:
        raise LogError(one_way)
    base = base_for(terms)
    Y = rows.extend(terms)
    result = _identified(robot, rows, base, Y, terms, urdf_tolerance)
    passive = [name for i, name in enumerate(robot.joint_names)
               if not np.any(log.u[:, i]) and i not in log.unmeasured]
    return Identification(result[0], result[1], result[2], velocity, used, velocity_window,
                          window, result[3], result[4], passive, terms, choice,
                          [robot.joint_names[i] for i in log.unmeasured])


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
                terms: JointTerms, urdf_tolerance: float):
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
                                       urdf_tolerance, score, terms)
    predictions = {
        "urdf": prediction_error(rows.core @ nominal, torque, mask, names),
        # the left-out equations' predictions do not count: Yb is 0 there
        "estimate": prediction_error(known_torque + Yb @ fit.theta, torque, mask, names),
        "consistent": prediction_error(Y @ projection.pi, torque, mask, names)}
    choice = choose_model(predictions, projection.pi,
                          np.concatenate([nominal, np.zeros(terms.count(robot.n))]),
                          [joint.child_link for joint in robot.joints])
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


def _assessment_json(result: Identification) -> dict:
    """summary.json's record of the training-log predictions, the consistent projection,
    what identified.urdf holds and the warnings."""
    out: dict = {"passive_joints": result.passive, "unmeasured_joints": result.unmeasured,
                 "warnings": result.warnings}
    if result.choice is not None:
        out["training_prediction"] = {
            **{name: p.as_json() for name, p in result.choice.predictions.items()},
            "definition": "RMS of (predicted - measured torque) over RMS of the measured "
                          "torque over the joint equations the regression used, per joint "
                          "and pooled; urdf: the input URDF, estimate: the base-parameter "
                          "least squares, consistent: the physically consistent parameters"}
        out["identified_urdf_holds"] = result.choice.written
    if result.projection is not None:
        out["consistency"] = result.projection.as_json()
    return out


def _terms_json(result: Identification, names: list[str]) -> dict:
    """summary.json's record of the extra joint terms and how they were chosen (none
    asked for: nothing)."""
    terms = result.terms
    chosen = ({} if result.terms_choice is None else
              {"joint_terms_choice": result.terms_choice.as_dict()})
    if not terms.any:
        return chosen
    n = len(names)
    values, errors = result.term_values(n), result.term_std_errors(n).reshape(n, -1)
    record: dict = {
        "terms": list(terms.kinds), "smooth_coulomb_velocity": terms.smooth_coulomb,
        "values": {name: dict(zip(terms.kinds, values[i].tolist()))
                   for i, name in enumerate(names)},
        "std_errors": {name: {kind: None if np.isnan(e) else float(e)
                              for kind, e in zip(terms.kinds, errors[i])}
                       for i, name in enumerate(names)},
        "written_to": SIDECAR_NAME if not result.urdf_kept else
        "nowhere: identified.urdf keeps the URDF's values"}
    if terms.asymmetric_coulomb:
        record["coulomb_in_urdf"] = "the mean of coulomb_positive and coulomb_negative"
    return {"joint_terms": record, **chosen}


def write_results(out: Path, robot: Robot, log: JointLog, result: Identification,
                  data_name: str) -> list[Path]:
    """velocities.csv, parameters.csv, identified.urdf, summary.json, a plot and
    joint_terms.csv (the extra joint terms; only its header without them or when
    identified.urdf keeps the URDF's values, so that validate never reads an earlier
    run's terms beside this run's URDF)."""
    out.mkdir(parents=True, exist_ok=True)
    names = robot.joint_names
    velocities = out / "velocities.csv"
    with velocities.open("w") as handle:  # in chunks: no copy of the log's length
        header = ",".join(["t"] + [f"qd{i + 1}" for i in range(robot.n)])
        for start in range(0, max(len(log.t), 1), WRITE_ROWS):
            rows = slice(start, start + WRITE_ROWS)
            np.savetxt(handle, np.column_stack([log.t[rows], result.velocity[rows]]),
                       delimiter=",", header=header if start == 0 else "", comments="")
    parameters = out / "parameters.csv"
    n = robot.n
    extra = result.terms.count(n)
    nominal_beta = result.base.project(np.concatenate([robot.parameters(), np.zeros(extra)]))
    consistent_beta = result.base.project(result.pi if result.projection is None
                                          else result.projection.pi)
    with parameters.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["parameter", "urdf", "estimate", "std_error", "consistent", "definition"])
        for k in range(result.base.count):
            writer.writerow([result.base.names[k], f"{nominal_beta[k]:.10g}",
                             f"{result.fit.theta[k]:.10g}", f"{result.fit.std_error[k]:.3g}",
                             f"{consistent_beta[k]:.10g}", result.base.description(k)])
    urdf = out / "identified.urdf"
    kept = result.urdf_kept
    standard = result.standard(n)
    layout = ParameterLayout(n, len(result.terms.kinds))
    write_identified_urdf(robot, standard, urdf,
                          f"the input URDF's inertials and joint dynamics, kept: the model "
                          f"identified from {data_name} predicts it worse (summary.json)"
                          if kept else
                          f"inertials and joint dynamics identified from {data_name} by "
                          f"python -m harness identify")
    sidecar = out / SIDECAR_NAME
    write_sidecar(sidecar, result.terms, names, [joint.kind for joint in robot.joints],
                  None if kept or not result.terms.any else result.pi[layout.extra],
                  result.term_std_errors(n))
    summary = out / "summary.json"
    write_json(summary, {
        "joints": names,
        "viscous": dict(zip(names, standard[layout.viscous_levels].tolist())),
        "coulomb": dict(zip(names, standard[layout.coulomb_levels].tolist())),
        "masses": dict(zip([j.child_link for j in robot.joints],
                           result.pi[layout.masses].tolist())),
        "residual_rms": dict(zip(names, result.fit.equation_rms.tolist())),
        "condition_number": result.fit.condition,
        "base_parameters": result.base.count,
        "samples_used": int(len(result.used)),
        "regression_window_s": result.window,
        "resampled": log.resampled,
        **_assessment_json(result),
        **_terms_json(result, names),
        **({} if result.velocity_window is None else
           {"velocity_window_s": dict(zip(names, result.velocity_window.tolist()))}),
    })
    plot = out / "velocities.png"
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    figure, axes = plt.subplots(n, 1, sharex=True, figsize=(8, 1.6 * n + 1), squeeze=False)
    for i in range(n):
        shown = plot_samples(result.velocity[:, i])
        axes[i, 0].plot(log.t[shown], result.velocity[shown, i], lw=0.8)
        axes[i, 0].set_ylabel(f"qd{i + 1}")
    axes[-1, 0].set_xlabel("t [s]")
    figure.tight_layout()
    figure.savefig(plot, dpi=90)
    plt.close(figure)
    return [velocities, parameters, urdf, summary, plot, sidecar]


def plot_samples(x: np.ndarray, bins: int = PLOT_BINS) -> np.ndarray | slice:
    """The samples of x (N,) that a line plot needs: all of a short signal; of a long
    one, the first and last and each of `bins` stretches' smallest and largest value
    in time order (the
    envelope the dense line fills at the plot's resolution, for a small part of the
    memory matplotlib takes for every point)."""
    if len(x) <= 2 * bins:
        return slice(None)
    width = -(-len(x) // bins)  # samples a stretch
    whole = len(x) // width * width
    stretches = x[:whole].reshape(-1, width)
    starts = np.arange(0, whole, width)[:, None]
    extremes = [starts + np.column_stack([stretches.argmin(axis=1), stretches.argmax(axis=1)])]
    if whole < len(x):
        rest = x[whole:]
        extremes.append(whole + np.array([[rest.argmin(), rest.argmax()]]))
    ends = np.array([[0, len(x) - 1]])  # the plot's time axis as the log's
    return np.unique(np.concatenate([ends, *extremes]))
