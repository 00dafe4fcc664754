"""The model-file commands: ``identify LOG --model MODEL.toml --out DIR`` and
``validate LOG --model MODEL.toml --out DIR`` (docs/model_files.md, "Identify and
validate").

identify: parameters by :func:`harness.model.identification.identify_model`, velocities by
the causal observer (:mod:`harness.model.estimates`). validate: the known side of each
equation reconstructed from the model's nominal values through the zero-phase pipeline.
Both also print and write the scores that share nothing with a pipeline
(:mod:`harness.model.scores`): the input reconstruction from raw central differences and
the free-run simulation error.

Exit status: 0 done; 1 written, but the result cannot be trusted (a weakly excited
unknown, a model that explains little of the log, a model whose simulation diverges;
said on stderr); 2 bad input (the model file, the log, an unknown the log does not
excite), nothing written.
"""
from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path
from typing import Any

import numpy as np

from ..json_files import write_json
from ..messages import note
from ..names import plain
from ..outputs import Outputs, shown
from .as_good import CLASS_TOLERANCE
from .errors import ModelFileError
from .estimates import Estimates
from .fit import relative_errors
from .identification import (
    HELD_SIGNIFICANT,
    WEAKLY_EXCITED,
    Identification,
    NotExcitedError,
    identify_model,
)
from .input_timing import InputTiming, choose_input_timing, held_fits_better
from .log import LogFileError, ModelLog, read_log
from .model import Model
from .reader import read_model
from .scores import independent_scores
from .selection import POWER_ABOVE, Choice
from .zero_phase import Regression, derivatives, regression

#: A pooled relative error above this on the estimation log: the model explains little.
POOR_FIT = 0.5

IDENTIFY_OUTPUTS = ("parameters.csv", "identified.toml", "estimates.csv", "estimates.png",
                    "identification.json")
VALIDATE_OUTPUTS = ("validation.json", "validation.png")


def _load(args: argparse.Namespace) -> tuple[Model, ModelLog]:
    model = read_model(args.model)
    log = read_log(args.data, model, args.sample_rate)
    if log.resampled:
        print(f"{args.data}: {log.resampled}")
    return model, log


def _fail(command: str, error: Exception) -> int:
    print(f"harness {command}: {error}", file=sys.stderr)
    return 2


def identify_command(args: argparse.Namespace) -> int:
    """``identify LOG --model MODEL.toml --out DIR``."""
    from ..tables import write_csv
    from .estimates import causal_estimates  # the native library: loaded when needed
    from .figures import plot_estimates
    from .writer import model_toml

    try:
        with Outputs(args.out, "identify", inputs=[args.data, args.model],
                     names=IDENTIFY_OUTPUTS) as outputs:
            model, log = _load(args)
            found = identify_model(model, log, args.refine)
            _check_finite(found)
            acceleration = derivatives(log, found.rows.settings).qdd
            estimates = causal_estimates(log, acceleration)
            scores = independent_scores(model, found.log, found.theta)
            _write_parameters(outputs.file("parameters.csv"), model, found)
            outputs.file("identified.toml").write_text(model_toml(
                model, found.theta, found.std_error,
                header=[f"{plain(Path(args.model).name)} identified from "
                        f"{plain(Path(args.data).name)} by sto-harness identify "
                        f"({found.method}); std errors: sandwich, 1 sigma"]),
                encoding="utf-8")
            columns: dict[str, np.ndarray] = {"t": log.t}
            for i, c in enumerate(model.coordinates):
                columns[c] = estimates.position[:, i]
                columns[f"der({c})"] = estimates.velocity[:, i]
            write_csv(outputs.file("estimates.csv"), columns)
            plot_estimates(log.t, estimates, model, outputs.file("estimates.png"))
            write_json(outputs.file("identification.json"),
                       {**_summary(found, estimates), **scores})
    except (ModelFileError, LogFileError, NotExcitedError, NotFiniteError) as error:
        return _fail("identify", error)
    print(f"wrote {shown(*outputs.written)}")
    width = max(len(p.name) for p in model.parameters)
    print(f"  parameters by {found.method}:")
    left_out = found.model_class.left_out if found.model_class else ()
    for k, p in enumerate(model.parameters):
        print(f"  {p.name:<{width}} = {found.theta[k]:.6g} {p.unit}   " +
              ("(optional, left out)" if p.name in left_out else
               f"(held at the {found.held[p.name]['end']} end of its range)"
               if p.name in found.held else f"+- {found.std_error[k]:.2g} (1 sigma)"))
    _print_class(found)
    _print_choice(found.choice, refined=found.method == "output error")
    if found.input_timing:
        _print_timing(found.input_timing)
    _print_refinement(found)
    print(f"  input reconstruction error on this log: {100 * found.pooled:.3f} % (through the "
          "chosen pipeline)")
    trusted = _print_scores(scores) and \
        not any(held["significant"] for held in found.held.values())
    _print_held(found)
    for p, e in zip(model.parameters, found.least_squares.excitation):
        if e < WEAKLY_EXCITED and p.name not in left_out:
            note(f"{p.name} is weakly excited by the log (excitation {e:.2g}, below "
                 f"{WEAKLY_EXCITED:g}): its value is uncertain beyond its standard error")
    if found.pooled > POOR_FIT:
        note(f"the model reconstructs the log's known side with a relative error of "
             f"{100 * found.pooled:.0f} %: it explains little of this log")
    return 0 if trusted else 1


class NotFiniteError(ValueError):
    """An estimate or standard error of identify is not a finite number."""


def _check_finite(found: Identification) -> None:
    """Every estimate and standard error identify would write is a finite number; else
    :class:`NotFiniteError` naming the first that is not (nothing is written)."""
    least = found.least_squares
    figures = (("estimate", found.theta), ("standard error", found.std_error),
               ("least-squares estimate", least.theta),
               ("least-squares standard error", least.std_error),
               ("least-squares classical standard error", least.classical_error))
    for what, values in figures:
        for k, p in enumerate(found.model.parameters):
            value = float(values[k])
            if not np.isfinite(value):
                raise NotFiniteError(
                    f"{found.log.source}: the {what} of {p.name} is {value}, not a finite "
                    "number: the log's values are too large (or too small) for double "
                    "precision in the model's equations; check the columns' units and "
                    "scaling (a force in N, not 1e200 N), or give [units] so they are "
                    "converted")


def _print_choice(choice: Choice, refined: bool) -> None:
    """The candidates' cross-validation scores and the choice; a band that leaves motion
    out is said: a warning when least squares are the answer, a remark when the output
    error (which no band limits) refined them."""
    if choice.candidates:
        scored = any(np.isfinite(c.input_score) for c in choice.candidates)
        print(f"  derivative pipeline by {choice.method}; per candidate, relative simulation "
              "error" + (", input error relative to the reference's, their product relative "
                         "to the best:" if scored else ":"))
        for c in choice.candidates:
            mark = "  <- chosen" if c.settings == choice.settings else ""
            figure = f"{100 * c.score:.4g} %" if np.isfinite(c.score) else "failed"
            if scored:
                figure = (f"{figure:>10}  {c.input_score:8.4g}  {c.combined:8.4g}"
                          if np.isfinite(c.combined) else f"{figure:>10}  failed")
            print(f"    {c.label:<58} {figure}{mark}")
    else:
        print(f"  derivative pipeline: {choice.method}")
    for name, share in choice.power_above.items():
        if share > POWER_ABOVE:
            text = (f"{name}: {100 * share:.1f} % of its motion's power lies above the chosen "
                    f"band ({choice.settings.cutoff:.4g} Hz)")
            if refined:
                print(f"  {text}; the output-error refinement saw all of it")
            else:
                note(f"{text}: least squares do not see it")


def _print_class(found: Identification) -> None:
    """Which optional unknowns the cross-validation kept, and what leaving each out
    alone would cost."""
    choice = found.model_class
    if choice is None:
        return
    print("  model class by cross-validation: " + (
        f"left out {', '.join(choice.left_out)}" if choice.left_out
        else "every optional unknown kept"))
    if choice.not_excited:
        print(f"    not excited by the log (left out first): {', '.join(choice.not_excited)}")
    for name, cost in choice.absence_costs.items():
        if cost > CLASS_TOLERANCE:
            print(f"    leaving out {name} costs {100 * cost:.3g} % on the cross-validated "
                  "error")
    for k, p in enumerate(found.model.parameters):  # the class is chosen on least squares
        if p.optional and p.name not in choice.left_out and \
                abs(found.theta[k]) < 2 * found.std_error[k]:
            print(f"    {p.name} = {found.theta[k]:.3g} is within 2 standard errors of 0 in "
                  f"the final estimate: this log hardly supports it")


def _print_held(found: Identification) -> None:
    """A declared range that the log pushes against is said, with where the least squares
    would put the unknown without it: a warning when that is more than HELD_SIGNIFICANT of
    its standard errors outside (the model class or the range may be wrong)."""
    for name, held in found.held.items():
        free, std = held["least_squares_without_range"], held["its_std_error"]
        text = (f"{name} is held at the {held['end']} end of its declared range, "
                f"{held['value']:g}" + (f" (least squares without the range: {free:.4g} +- "
                                        f"{std:.2g})" if free is not None else ""))
        if held["significant"]:
            note(f"{text}: the log pushes it outside the range the model file declares by "
                 f"more than {HELD_SIGNIFICANT:g} standard errors; its standard error is 0 "
                 "and the others' are those with it fixed. Check the model's terms, or "
                 "whether the log excites it")
        else:
            print(f"  {text}: within {HELD_SIGNIFICANT:g} standard errors of the range")


def _print_timing(timing: InputTiming) -> None:
    """How the inputs act between samples, why, and the runs' errors of both timings."""
    scores = ", ".join(f"{name} {100 * e:.4g} %" if np.isfinite(e) else f"{name} diverges"
                       for name, e in timing.scores.items())
    print(f"  inputs between samples: {timing.name} ({timing.method}"
          f"{'; runs error ' + scores if scores else ''})")
    if held_fits_better(timing):
        print("    the runs follow the log better with the inputs held: if they are a "
              "digital controller's output, held over each sample, declare [log] inputs = "
              "\"held\" in the model file")


def _print_refinement(found: Identification) -> None:
    info = found.refinement
    held_out = info.get("held_out_simulation_error")
    if isinstance(held_out, dict):
        halves = held_out["per_half"]
        print("  held-out simulation error (each half's fit scored on the other half): "
              "least squares " + _halves(halves["least_squares"]) + ", refined "
              + _halves(halves["refined"]) + f" (ratio {held_out['ratio']:.3g})")
    if info.get("applied"):
        print(f"  output-error refinement: run error {100 * info['runs_error_start']:.4g} "
              f"% -> {100 * info['runs_error_end']:.4g} % ({info['evaluations']} "
              "evaluations)")
        if info.get("std_error_from_halves"):
            print("    standard errors from the halves' refined estimates (half their "
                  "difference, larger than the sandwich's): "
                  + ", ".join(info["std_error_from_halves"]))
    else:
        print(f"  output-error refinement not applied: {info.get('reason')}")


def _halves(errors: list[float]) -> str:
    return " and ".join(f"{100 * e:.4g}" for e in errors) + " %"


def _print_scores(scores: dict[str, Any]) -> bool:
    """The scores that share nothing with the pipeline; a diverging simulation and a model
    that creates energy are said (False: the model is not to be trusted)."""
    trusted = True
    reconstruction = scores["reconstruction_error"]
    if reconstruction["pooled"] is not None:
        print(f"  input reconstruction, raw central differences at the full rate: "
              f"{100 * float(reconstruction['pooled']):.3f} %")
    simulation = scores["simulation_error"]
    if simulation["diverged_at_s"] is None:
        for name, e in simulation["per_coordinate"].items():
            print(f"  free-run simulation error of {name}: {e['rms']:.4g} {e['unit']} RMS, "
                  f"{100 * e['relative']:.3f} % of its motion")
        if simulation["pooled"] is not None and simulation["pooled"] > 1.0:
            print("    the free run ends farther from the log than the motion itself: open "
                  "loop, it cannot follow a machine that ran in closed loop (or one whose "
                  "friction model differs where it sticks), so this score cannot rank "
                  "models on this log; the held-out runs and the input reconstruction can")
    else:
        note(f"the model's simulation driven by the measured input diverges after "
             f"{simulation['diverged_at_s']:.4g} s: the model is unstable on this log (or "
             "the machine runs in closed loop, which the model file does not describe)")
        trusted = False
    energy = scores["creates_energy"]
    if energy is not None and energy["share"] > 0:
        note(f"the model creates energy: near rest at {100 * energy['share']:.0f} % of the "
             f"log's positions the friction of {energy['coordinate']} is negative (a "
             "negative viscous damping or Coulomb level), so its free response grows; "
             "declare the friction parameters positive = true in the model file")
        trusted = False
    return trusted


def _write_parameters(path: Path, model: Model, result: Identification) -> None:
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(["name", "value", "std_error", "unit"])
        for k, p in enumerate(model.parameters):
            writer.writerow([p.name, repr(float(result.theta[k])),
                             repr(float(result.std_error[k])), p.unit])


def _summary(found: Identification, estimates: Estimates) -> dict[str, object]:
    model, least = found.model, found.least_squares
    return {
        "model": model.source, "log": found.log.source, "samples": found.log.samples,
        "resampled": found.log.resampled, "method": found.method,
        "parameters": {p.name: {"value": float(found.theta[k]),
                                "std_error": float(found.std_error[k]),
                                "excitation": float(least.excitation[k]), "unit": p.unit}
                       for k, p in enumerate(model.parameters)},
        "std_error": ("sandwich over the runs, initial states profiled out, 1 sigma"
                      if found.method == "output error" else
                      "sandwich over batches of consecutive regressor rows, 1 sigma"),
        "least_squares": {p.name: {"value": float(least.theta[k]),
                                   "std_error": float(least.std_error[k]),
                                   "classical_std_error": float(least.classical_error[k])}
                          for k, p in enumerate(model.parameters)},
        "refinement": found.refinement,
        "held_at_range": found.held,
        "input_timing": found.input_timing.as_dict() if found.input_timing else None,
        "model_class": found.model_class.as_dict() if found.model_class else None,
        "relative_error": {"per_equation": found.per_equation, "pooled": found.pooled},
        "pipeline": found.rows.settings.as_dict(), "rows": least.rows,
        "pipeline_choice": found.choice.as_dict(),
        "velocity": {"estimator": "causal observer (harness.robot.native.observe_adaptive)",
                     "noise_std": {c: float(np.median(estimates.noise[:, i]))
                                   for i, c in enumerate(model.coordinates)}},
    }


def validate_model(model: Model, log: ModelLog) -> tuple[Regression, np.ndarray,
                                                          list[float | None], float]:
    """The known side of each equation and its reconstruction from the model's nominal
    values through the zero-phase pipeline; the relative errors per equation and pooled."""
    rows = regression(model, log)
    predicted = rows.Y @ model.nominal
    per, pooled = relative_errors(rows.Y, rows.r, model.nominal)
    return rows, predicted, per, pooled


def validate_command(args: argparse.Namespace) -> int:
    """``validate LOG --model MODEL.toml --out DIR``."""
    from .figures import plot_validation

    try:
        with Outputs(args.out, "validate", inputs=[args.data, args.model],
                     names=VALIDATE_OUTPUTS) as outputs:
            model, log = _load(args)
            timing = choose_input_timing(model, log, None, model.nominal)
            log = timing.log  # a held input's samples, half a sample later
            rows, predicted, per, pooled = validate_model(model, log)
            scores = independent_scores(model, log, model.nominal)
            write_json(outputs.file("validation.json"), {
                "model": model.source, "log": log.source, "resampled": log.resampled,
                "relative_error": {"per_equation": per, "pooled": pooled},
                "definition": "norm of (Y theta - r) over norm of r on the decimated rows of "
                              "the zero-phase pipeline; r: each equation's known side",
                "parameters": {p.name: p.nominal for p in model.parameters},
                "pipeline": rows.settings.as_dict(), "rows": int(rows.Y.shape[0]),
                "input_timing": timing.as_dict(), **scores,
            })
            plot_validation(rows.t, rows.r, predicted, model, outputs.file("validation.png"),
                            f"validate: {Path(args.data).name}, relative error "
                            f"{100 * pooled:.2f} %")
    except (ModelFileError, LogFileError) as error:
        return _fail("validate", error)
    print(f"wrote {shown(*outputs.written)}")
    for i, e in enumerate(per, start=1):
        print(f"  equation {i}: relative error "
              + ("n/a (its known side is zero)" if e is None else f"{100 * e:.3f} %"))
    print(f"  pooled: {100 * pooled:.3f} % (through the zero-phase pipeline)")
    _print_timing(timing)
    return 0 if _print_scores(scores) else 1
