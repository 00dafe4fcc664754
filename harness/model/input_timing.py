"""How a log's inputs act between their samples: as the model file declares ([log] inputs),
with the evidence of the data shown.

A drive's or a robot's input is usually a digital controller's output, held from one
sample to the next: a zero-order hold, which below the sample rate is a delay of half a
sample (and a gain of sinc(f / fs), 0.9993 at fs / 50). Taken as samples of a continuous
signal instead, the model sees its input half a sample early: the least squares pair
each acceleration with the force of the next half sample, and the output-error
refinement pays for it in the parameters (on a simulated EMPS-like drive at 1 kHz, M 0.3
% high: ten of its standard errors). A log declared held ([log] inputs = "held") is
therefore identified from its inputs delayed by half a sample (:func:`held_inputs`),
through the same pipeline. The samples cannot show which of the two the machine did; the
model can hint: each timing's least squares on the chosen pipeline, simulated in runs
from the measured states. identify reports both runs' errors; the default stays
"sampled", and a held timing that simulates the log better is said, for the user to
declare: on the EMPS drive the held runs follow the log better (0.44 % against 0.58 %),
yet the benchmark's independent scores of the held estimate are not (cross-test 5.97 %
against 5.94 %, closed-loop force 6.72 % against 6.53 %), so the evidence of the runs
alone does not decide.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .fit import estimate
from .log import ModelLog
from .model import Model
from .refine import CHECK_ITERATIONS, MOST_RUNS, run_length
from .scores import PieceSimulator, linearized_over, pieces
from .simulation import Dynamics, input_at, substeps, time_constant
from .zero_phase import ZeroPhase, regression


@dataclass(frozen=True)
class InputTiming:
    """``held``: the inputs act through a zero-order hold, and ``log`` is the log with its
    inputs delayed by half a sample (else the log itself); ``method``: how that was
    decided; ``scores``: the runs' relative position error with each timing."""

    held: bool
    log: ModelLog
    method: str
    scores: dict[str, float] = field(default_factory=dict)

    @property
    def name(self) -> str:
        return "held" if self.held else "sampled"

    def as_dict(self) -> dict[str, object]:
        return {"inputs": self.name, "method": self.method,
                "runs_error": {name: float(e) if np.isfinite(e) else None  # diverged: None
                               for name, e in self.scores.items()}}


def held_inputs(log: ModelLog) -> ModelLog:
    """The log with its inputs half a sample later (band-limited interpolation; the first
    sample keeps its value): what a zero-order hold's inputs do at the sample instants."""
    if not log.inputs.shape[1]:
        return log
    half = input_at(log.inputs, log.step, 1)  # every half sample
    return replace(log, inputs=np.concatenate([log.inputs[:1], half[1:-1:2]]))


def _timed(model: Model, log: ModelLog, held: bool, method: str,
           scores: dict[str, float] | None = None) -> InputTiming:
    return InputTiming(held, held_inputs(log) if held else log, method, scores or {})


def choose_input_timing(model: Model, log: ModelLog, settings: ZeroPhase | None,
                        theta: np.ndarray | None = None) -> InputTiming:
    """The model file's [log] inputs, else sampled; undeclared, the runs' errors of both
    timings are scored (:func:`held_fits_better`): with parameters ``theta`` when given
    (validate), else each timing's own least squares on the pipeline ``settings`` (None:
    the default pipeline)."""
    if model.input_timing is not None:
        return _timed(model, log, model.input_timing == "held", "declared by the model file")
    if not model.inputs:
        return _timed(model, log, False, "no inputs")
    try:
        scores = _runs_errors(model, log, settings, theta)
    except (ValueError, ArithmeticError, np.linalg.LinAlgError) as error:
        return _timed(model, log, False, f"the default; the timings not compared ({error})")
    if scores is None:
        return _timed(model, log, False, "too short to tell: taken as sampled")
    return _timed(model, log, False, "the default (declare [log] inputs to choose)", scores)


def _runs_errors(model: Model, log: ModelLog, settings: ZeroPhase | None,
                 theta: np.ndarray | None) -> dict[str, float] | None:
    """Each timing's runs' relative position error (None: too few runs)."""
    dynamics = Dynamics(model)
    scores: dict[str, float] = {}
    for held in (False, True):
        timed = held_inputs(log) if held else log
        values = theta
        if values is None:
            rows = regression(model, timed, settings)
            values = estimate(rows.Y, rows.r, model.nominal, mask=rows.mask,
                              bounds=model.bounds)
        A = linearized_over(dynamics, timed, values)
        runs = pieces(0, log.samples, run_length(timed, time_constant(A)), MOST_RUNS)
        if len(runs.starts) < 2:
            return None
        simulator = PieceSimulator(dynamics, timed, runs, substeps(A, log.step))
        with np.errstate(all="ignore"):  # a run that diverges scores inf or nan
            scores["held" if held else "sampled"] = simulator.error(values, CHECK_ITERATIONS)
    return scores


def held_fits_better(timing: InputTiming) -> bool:
    """Undeclared, the runs with the inputs held follow the log better than sampled."""
    scores = timing.scores
    return (not timing.held and "held" in scores and "sampled" in scores and
            bool(np.isfinite(scores["held"])) and scores["held"] < scores["sampled"])
