"""The model-file commands: ``identify LOG --model MODEL.toml --out DIR`` and
``validate LOG --model MODEL.toml --out DIR`` (docs/model_files.md, "Identify and
validate").

identify: parameters by least squares on the zero-phase pipeline's regressor rows
(:mod:`harness.model.zero_phase`, :mod:`harness.model.fit`), velocities by the causal
observer (:mod:`harness.model.estimates`). validate: the known side of each equation
reconstructed from the model's nominal values through the same pipeline.

Exit status: 0 done; 1 written, but the result cannot be trusted (a weakly excited
unknown, a model that explains little of the log; said on stderr); 2 bad input (the
model file, the log, an unknown the log does not excite), nothing written.
"""
from __future__ import annotations

import argparse
import csv
import json
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..messages import note
from ..outputs import Outputs
from .errors import ModelFileError
from .estimates import Estimates
from .fit import Fit, fit, relative_errors
from .log import LogFileError, ModelLog, read_log
from .model import Model
from .reader import read_model
from .zero_phase import Regression, derivatives, regression

#: An unknown whose excitation (fit.excitation) is below this is refused (exit 2) ...
NOT_EXCITED = 1e-3
#: ... below this it is identified with a warning (exit 1).
WEAKLY_EXCITED = 1e-2
#: A pooled relative error above this on the estimation log: the model explains little.
POOR_FIT = 0.5

IDENTIFY_OUTPUTS = ("parameters.csv", "identified.toml", "estimates.csv", "estimates.png",
                    "identification.json")
VALIDATE_OUTPUTS = ("validation.json", "validation.png")


class NotExcitedError(ValueError):
    """The log leaves an unknown undetermined (exit status 2)."""


@dataclass(frozen=True)
class Identification:
    """What identify found on one log."""

    model: Model
    log: ModelLog
    rows: Regression
    result: Fit
    per_equation: list[float | None]
    pooled: float


def identify_model(model: Model, log: ModelLog) -> Identification:
    """The unknowns of ``model`` from ``log``; NotExcitedError names an unknown the log
    does not excite, with its excitation figure."""
    rows = regression(model, log)
    result = fit(rows.Y, rows.r, model.nominal)
    low = [(p.name, e) for p, e in zip(model.parameters, result.excitation) if e < NOT_EXCITED]
    if low:
        figures = ", ".join(f"{name} (excitation {e:.2g})" for name, e in low)
        raise NotExcitedError(
            f"{log.source}: the log does not excite {figures}: the column of each in the "
            f"regressor is zero on the log or a combination of the other columns "
            f"(excitation = the share of the column the others do not explain, 0 to 1; "
            f"below {NOT_EXCITED:g} is refused). Use a log in which this term varies "
            "independently, or make it a constant of the model")
    per, pooled = relative_errors(rows.Y, rows.r, result.theta)
    return Identification(model, log, rows, result, per, pooled)


def _load(args: argparse.Namespace) -> tuple[Model, ModelLog]:
    model = read_model(args.model)
    return model, read_log(args.data, model)


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
            found = identify_model(model, log)
            acceleration = derivatives(log, found.rows.settings).qdd
            estimates = causal_estimates(log, acceleration)
            result = found.result
            _write_parameters(outputs.file("parameters.csv"), model, result)
            outputs.file("identified.toml").write_text(model_toml(
                model, result.theta, result.std_error,
                header=[f"{Path(args.model).name} identified from {Path(args.data).name} by "
                        "sto-harness identify; std errors: sandwich, 1 sigma"]),
                encoding="utf-8")
            columns: dict[str, np.ndarray] = {"t": log.t}
            for i, c in enumerate(model.coordinates):
                columns[c] = estimates.position[:, i]
                columns[f"der({c})"] = estimates.velocity[:, i]
            write_csv(outputs.file("estimates.csv"), columns)
            plot_estimates(log.t, estimates, model, outputs.file("estimates.png"))
            outputs.file("identification.json").write_text(json.dumps(
                _summary(found, estimates), indent=2) + "\n", encoding="utf-8")
    except (ModelFileError, LogFileError, NotExcitedError) as error:
        return _fail("identify", error)
    print(f"wrote {', '.join(str(p) for p in outputs.written)}")
    width = max(len(p.name) for p in model.parameters)
    for k, p in enumerate(model.parameters):
        print(f"  {p.name:<{width}} = {result.theta[k]:.6g} {p.unit}   +- "
              f"{result.std_error[k]:.2g} (1 sigma)")
    print(f"  input reconstruction error on this log: {100 * found.pooled:.3f} %")
    for p, e in zip(model.parameters, result.excitation):
        if e < WEAKLY_EXCITED:
            note(f"{p.name} is weakly excited by the log (excitation {e:.2g}, below "
                 f"{WEAKLY_EXCITED:g}): its value is uncertain beyond its standard error")
    if found.pooled > POOR_FIT:
        note(f"the model reconstructs the log's known side with a relative error of "
             f"{100 * found.pooled:.0f} %: it explains little of this log")
    return 0


def _write_parameters(path: Path, model: Model, result: Fit) -> None:
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(["name", "value", "std_error", "unit"])
        for k, p in enumerate(model.parameters):
            writer.writerow([p.name, repr(float(result.theta[k])),
                             repr(float(result.std_error[k])), p.unit])


def _summary(found: Identification, estimates: Estimates) -> dict[str, object]:
    model, result = found.model, found.result
    return {
        "model": model.source, "log": found.log.source, "samples": found.log.samples,
        "parameters": {p.name: {"value": float(result.theta[k]),
                                "std_error": float(result.std_error[k]),
                                "classical_std_error": float(result.classical_error[k]),
                                "excitation": float(result.excitation[k]), "unit": p.unit}
                       for k, p in enumerate(model.parameters)},
        "std_error": "sandwich over batches of consecutive regressor rows, 1 sigma",
        "relative_error": {"per_equation": found.per_equation, "pooled": found.pooled},
        "pipeline": found.rows.settings.as_dict(), "rows": result.rows,
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
            rows, predicted, per, pooled = validate_model(model, log)
            outputs.file("validation.json").write_text(json.dumps({
                "model": model.source, "log": log.source,
                "relative_error": {"per_equation": per, "pooled": pooled},
                "definition": "norm of (Y theta - r) over norm of r on the decimated rows of "
                              "the zero-phase pipeline; r: each equation's known side",
                "parameters": {p.name: p.nominal for p in model.parameters},
                "pipeline": rows.settings.as_dict(), "rows": int(rows.Y.shape[0]),
            }, indent=2) + "\n", encoding="utf-8")
            plot_validation(rows.t, rows.r, predicted, model, outputs.file("validation.png"),
                            f"validate: {Path(args.data).name}, relative error "
                            f"{100 * pooled:.2f} %")
    except (ModelFileError, LogFileError) as error:
        return _fail("validate", error)
    print(f"wrote {', '.join(str(p) for p in outputs.written)}")
    for i, e in enumerate(per, start=1):
        print(f"  equation {i}: relative error "
              + ("n/a (its known side is zero)" if e is None else f"{100 * e:.3f} %"))
    print(f"  pooled: {100 * pooled:.3f} %")
    return 0
