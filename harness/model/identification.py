"""The identification of a model file's unknowns from a log, as ``identify --model`` runs it:

1. the derivative pipeline chosen by blocked cross-validation
   (:func:`harness.model.selection.choose_pipeline`);
2. how the inputs act between samples, held or sampled
   (:func:`harness.model.input_timing.choose_input_timing`);
3. least squares on its regressor rows (:func:`harness.model.fit.fit`), refused when an
   unknown is not excited; the parameters marked optional kept or left out (at 0) by the
   same cross-validation (:func:`harness.model.selection.choose_class`);
4. the output-error refinement (:mod:`harness.model.refine`): always, never, or (auto)
   when it lowers the simulation error on held-out halves of the log.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .fit import BATCH_SAMPLES, Fit, expanded, fit, relative_errors
from .input_timing import InputTiming, choose_input_timing
from .log import ModelLog
from .model import Model
from .refine import check_on_halves, refine
from .selection import Choice, ClassChoice, choose_class, choose_pipeline
from .simulation import Dynamics
from .zero_phase import Regression, regression

#: An unknown whose excitation (fit.excitation) is below this is refused (exit 2) ...
NOT_EXCITED = 1e-3
#: ... below this it is identified with a warning (exit 1).
WEAKLY_EXCITED = 1e-2
REFINE_MODES = ("auto", "simulation", "none")
#: A declared range the log pushes an unknown past by more than this many standard
#: errors (of the least squares without the ranges) is a warning (exit 1); less is a
#: remark: a true value at the range's end lands outside it half the time.
HELD_SIGNIFICANT = 2.0


class NotExcitedError(ValueError):
    """The log leaves an unknown undetermined (exit status 2)."""


@dataclass(frozen=True)
class Identification:
    """What identify found on one log: the estimate (``theta``, ``std_error``), the least
    squares it started from, and how each choice was made."""

    model: Model
    log: ModelLog
    rows: Regression
    least_squares: Fit
    theta: np.ndarray
    std_error: np.ndarray     # 1 sigma
    method: str               # "least squares" or "output error"
    per_equation: list[float | None]
    pooled: float
    choice: Choice
    refinement: dict[str, Any] = field(default_factory=dict)
    model_class: ClassChoice | None = None   # None: no parameter is optional
    #: the unknowns the estimate holds at an end of their declared range: name -> the end
    #: ("lower", "upper") and the least squares without the ranges (None if they kept it)
    held: dict[str, dict[str, Any]] = field(default_factory=dict)
    #: how the inputs act between samples (``log`` is the log as identified: a held
    #: input's samples half a sample later)
    input_timing: InputTiming | None = None


def identify_model(model: Model, log: ModelLog, refine_mode: str = "auto") -> Identification:
    """The unknowns of ``model`` from ``log``; NotExcitedError names an unknown the log does
    not excite, with its excitation figure."""
    if refine_mode not in REFINE_MODES:
        raise ValueError(f"refine mode {refine_mode!r} is not one of {', '.join(REFINE_MODES)}")
    choice = choose_pipeline(model, log)
    timing = choose_input_timing(model, log, choice.settings)
    log = timing.log  # a held input's samples, half a sample later
    rows = regression(model, log, choice.settings)
    if not np.any(rows.r):
        raise NotExcitedError(
            f"{log.source}: the known side of every equation (the terms without unknowns, "
            f"such as the inputs {', '.join(model.inputs) or '(none)'}) is zero on the log: "
            "any multiple of the unknowns fits it as well, so their scale cannot be told. "
            "Use a log in which the input acts, or make one unknown a constant of the model")
    batch = max(1, round(BATCH_SAMPLES / choice.settings.decimation))
    least = fit(rows.Y, rows.r, model.nominal, batch=batch, mask=rows.mask,
                bounds=model.bounds)
    low = [(p.name, e) for p, e in zip(model.parameters, least.excitation)
           if e < NOT_EXCITED and not p.optional]
    if low:
        figures = ", ".join(f"{name} (excitation {e:.2g})" for name, e in low)
        raise NotExcitedError(
            f"{log.source}: the log does not excite {figures}: the column of each in the "
            f"regressor is zero on the log or a combination of the other columns "
            f"(excitation = the share of the column the others do not explain, 0 to 1; "
            f"below {NOT_EXCITED:g} is refused). Use a log in which this term varies "
            "independently, mark it optional = true, or make it a constant of the model")
    model_class = None
    free = np.ones(len(model.parameters), dtype=bool)
    if any(p.optional for p in model.parameters):
        model_class = choose_class(model, log, rows, choice.settings.border, least.excitation,
                                   NOT_EXCITED)
        free = model_class.free
        if not free.all():
            lower, upper = model.bounds
            least = expanded(fit(rows.Y[:, :, free], rows.r, model.nominal[free],
                                  batch=batch, mask=rows.mask,
                                  bounds=(lower[free], upper[free])), free, least.excitation)
    held = np.zeros(len(free), dtype=bool) if least.at_bound is None else least.at_bound != 0
    theta, std, method, info = _refined(model, log, rows, least, refine_mode, free & ~held)
    per, pooled = relative_errors(rows.Y, rows.r, theta)
    return Identification(model, log, rows, least, theta, std, method, per, pooled, choice,
                          info, model_class, _held(model, theta, least), timing)


def _held(model: Model, theta: np.ndarray, least: Fit) -> dict[str, dict[str, Any]]:
    """The unknowns at an end of their declared range (the least squares' active set, or
    where the refinement stopped on it), with the unbounded least squares' value."""
    out: dict[str, dict[str, Any]] = {}
    for k, p in enumerate(model.parameters):
        for end, value in (("lower", p.lower), ("upper", p.upper)):
            if np.isfinite(value) and abs(theta[k] - value) <= 1e-9 * max(1.0, abs(value)):
                free, std = ((None, None) if least.unbounded is None or
                             least.unbounded_std is None else
                             (float(least.unbounded[k]), float(least.unbounded_std[k])))
                out[p.name] = {"end": end, "value": value,
                               "least_squares_without_range": free,
                               "its_std_error": std,
                               "significant": free is not None and std is not None and
                               abs(free - value) > HELD_SIGNIFICANT * std}
    return out


def _refined(model: Model, log: ModelLog, rows: Regression, least: Fit, mode: str,
             free: np.ndarray) -> tuple[np.ndarray, np.ndarray, str, dict[str, Any]]:
    """The estimate after the refinement ``mode`` asks for (the unknowns ``free`` move),
    and what was done."""
    kept = (least.theta, least.std_error, "least squares")
    if mode == "none":
        return (*kept, {"mode": mode, "applied": False, "reason": "--refine none"})
    dynamics = Dynamics(model)
    info: dict[str, Any] = {"mode": mode}
    start = least.theta
    check = None
    try:
        if mode == "auto":
            check = check_on_halves(model, log, rows, least.theta, dynamics, free)
            info["held_out_simulation_error"] = check.as_dict()
            if not check.improves:
                return (*kept, {**info, "applied": False,
                                "reason": "it does not lower the simulation error on "
                                          "the held-out halves (the geometric mean of "
                                          "their ratios)"})
            start = check.start()  # nearer the optimum than least squares: fewer steps
        result = refine(model, log, start, dynamics=dynamics, free=free)
    except (ValueError, np.linalg.LinAlgError, FloatingPointError) as error:
        return (*kept, {**info, "applied": False, "reason": f"the refinement failed ({error})"})
    if not (np.all(np.isfinite(result.theta)) and np.all(np.isfinite(result.std_error))):
        return (*kept, {**info, "applied": False,
                        "reason": "the refinement ended on non-finite values"})
    info.update({"applied": True, "runs_error_start": result.cost_start,
                 "runs_error_end": result.cost_end, "evaluations": result.evaluations,
                 "solver": result.status})
    std = result.std_error
    if check is not None:  # the larger of the sandwich's and the halves' spread
        spread = np.where(free, check.spread(), 0.0)
        std = np.maximum(std, spread)
        names = [p.name for p in model.parameters]
        info["halves_std_error"] = dict(zip(names, spread.tolist()))
        info["std_error_from_halves"] = [name for name, s, w in
                                         zip(names, spread, result.std_error) if s > w]
    return result.theta, std, "output error", info
