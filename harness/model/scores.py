"""Scores of a model on a log that share none of the identification pipeline's choices.

* **Reconstruction**: the model's input side computed from the raw positions at the full
  sample rate (velocities and accelerations by central differences, no filter, no
  decimation) against the raw measured input. Noise in the positions enters the
  accelerations here unfiltered, so on a noisy log this figure has a floor, and it
  favours models that weigh the accelerations less: read it beside the simulation.
* **Energy**: whether the model's friction gives energy near rest at the log's positions
  (core/model_damping.h, the model FMU's ``negative_damping``): a model that does has a
  growing free response, whatever this log's simulation shows.
* **Simulation**: the model driven by the measured input from the measured initial state
  (position as logged, velocity by spectral differentiation), free run over the whole
  log; the RMS of each coordinate's error in its unit and relative to the RMS of the coordinate's
  motion (about its mean). A run that diverges says so.

:class:`PieceSimulator` is the simulation score over short runs of a log, each from its
measured state: what the cross-validation and the output-error refinement minimize.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .fit import relative_errors
from .log import ModelLog
from .model import Model
from .program import ProgramError, compile_program, energy_check
from .simulation import (
    Dynamics,
    Run,
    input_at,
    linearized,
    simulate,
    substeps,
)
from .zero_phase import spectral


def reference_velocity(log: ModelLog) -> np.ndarray:
    """The velocities the simulations start from (samples, coordinates): spectral
    differentiation of the positions. Only a first guess of a run's initial state (exact
    for a band-limited motion, noisy where the positions are): the runs fit their initial
    state."""
    return spectral(log.q, log.step, 1)


#: The log's states at which the energy check runs (evenly spread).
ENERGY_STATES = 200


def independent_scores(model: Model, log: ModelLog, theta: np.ndarray) -> dict[str, Any]:
    """The scores of a model on a log that share nothing with the pipeline, by their keys
    in identification.json and validation.json."""
    return {"reconstruction_error": reconstruction_error(model, log, theta),
            "simulation_error": simulation_error(model, log, theta),
            "creates_energy": creates_energy(model, log, theta)}


def creates_energy(model: Model, log: ModelLog, theta: np.ndarray) -> dict[str, Any] | None:
    """At ENERGY_STATES of the log's positions and inputs, whether the model's friction
    gives energy near rest; the share of those states and the first coordinate whose
    friction does. None for a model the core's term program cannot hold (not checked)."""
    try:
        text = compile_program(model)
    except ProgramError:
        return None
    take = np.unique(np.linspace(0, log.samples - 1, ENERGY_STATES).round().astype(int))
    inputs = log.inputs[take] if model.inputs else np.zeros((len(take), 0))
    which = energy_check(text, np.asarray(theta, float), log.q[take], inputs)
    bad = which[which > 0]
    return {"share": float(len(bad) / len(take)), "states": int(len(take)),
            "coordinate": model.coordinates[bad[0] - 1] if len(bad) else None,
            "definition": "near rest at the log's positions: the damping d equations / d "
                          "velocities has a negative eigenvalue or a Coulomb level is "
                          "negative (the model's free response grows)"}


def reconstruction_error(model: Model, log: ModelLog, theta: np.ndarray) -> dict[str, Any]:
    """|Y theta - r| / |r| per equation and pooled, Y and r from central differences of
    the raw positions and the raw inputs at every sample."""
    qd = np.gradient(log.q, log.step, axis=0)
    qdd = np.gradient(qd, log.step, axis=0)
    Y, r = model.regressor(log.q, qd, qdd, log.inputs if model.inputs else None)
    per, pooled = relative_errors(Y, r, theta)
    return {"per_equation": per, "pooled": pooled if math.isfinite(pooled) else None,
            "definition": "norm of (Y theta - r) over norm of r at every sample, Y and r "
                          "from the raw positions (central differences) and raw inputs"}


def motion_rms(log: ModelLog) -> np.ndarray:
    """Each coordinate's RMS about its mean: the yardstick of the relative errors."""
    return np.sqrt(np.mean((log.q - log.q.mean(axis=0)) ** 2, axis=0))


@dataclass(frozen=True)
class Pieces:
    """Short runs over a log: their first samples and their length in samples."""

    starts: np.ndarray
    length: int


def pieces(first: int, last: int, length: int, most: int) -> Pieces:
    """Non-overlapping runs of ``length`` samples within samples [first, last), at most
    ``most`` of them, spread evenly."""
    count = max((last - first) // length, 0)
    starts = first + length * np.arange(count)
    if count > most:
        starts = starts[np.linspace(0, count - 1, most).round().astype(int)]
    return Pieces(starts, length)


class PieceSimulator:
    """The runs of :class:`Pieces` of one log for any parameters: their inputs and measured
    states are gathered once."""

    def __init__(self, dynamics: Dynamics, log: ModelLog, runs: Pieces, parts: int) -> None:
        self.dynamics, self.log, self.runs, self.parts = dynamics, log, runs, parts
        fine = input_at(log.inputs, log.step, parts)   # the whole log's input, once
        stride = 2 * parts
        offsets = np.arange(stride * (runs.length - 1) + 1)
        self.u = fine[runs.starts[:, None] * stride + offsets[None, :]]
        index = runs.starts[:, None] + np.arange(runs.length)[None, :]
        self.measured = log.q[index]                          # (runs, length, n)
        self.q0 = log.q[runs.starts]
        self.qd0 = reference_velocity(log)[runs.starts]
        self.span = np.ptp(log.q, axis=0) + 1e-300
        self.motion = np.where(motion_rms(log) > 0, motion_rms(log), 1.0)

    def run(self, theta: np.ndarray, q0: np.ndarray | None = None,
            qd0: np.ndarray | None = None) -> Run:
        """The runs for parameters theta (p,) or per run (runs, p), from the measured
        states or from q0, qd0 (runs, n)."""
        return simulate(self.dynamics, theta, self.q0 if q0 is None else q0,
                        self.qd0 if qd0 is None else qd0, self.u, self.log.step,
                        self.parts, self.span)

    def residuals(self, theta: np.ndarray, iterations: int = 1) -> np.ndarray:
        """Measured minus simulated positions (runs, length, n), each run's initial state
        fitted by Gauss-Newton (``iterations`` steps from the measured state, which is only
        a first guess: a local fit's velocity is poor where the motion is fast)."""
        runs, length, n = self.measured.shape
        theta = np.broadcast_to(theta, (runs, np.shape(theta)[-1]))
        velocity_scale = np.sqrt(np.mean(self.qd0 ** 2, axis=0))
        velocity_scale = np.where(velocity_scale > 0, velocity_scale, self.motion / self.log.step)
        deltas = np.concatenate([1e-4 * self.motion, 1e-4 * velocity_scale])
        copies = 2 * n + 1
        thetas, inputs = np.concatenate([theta] * copies), np.concatenate([self.u] * copies)
        state = np.concatenate([self.q0, self.qd0], axis=1)
        measured = self.measured.reshape(runs, -1)
        for iteration in range(iterations + 1):
            starts = [state] + [state + deltas[j] * (np.arange(2 * n) == j) for j in range(2 * n)]
            start = np.concatenate(starts)
            with np.errstate(all="ignore"):
                sim = simulate(self.dynamics, thetas, start[:, :n], start[:, n:], inputs,
                               self.log.step, self.parts, self.span)
            q = sim.q.reshape(copies, runs, length * n)
            error = measured - q[0]
            if iteration == iterations:
                return error.reshape(runs, length, n)
            S = np.stack([(q[j + 1] - q[0]) / deltas[j] for j in range(2 * n)], axis=2)
            normal = np.einsum("rsi,rsj->rij", S, S)
            normal += 1e-12 * np.einsum("rii->r", normal)[:, None, None] * np.eye(2 * n)
            rhs = np.einsum("rsi,rs->ri", S, error)[:, :, None]
            with np.errstate(all="ignore"):  # pinv: a run whose state does not act is left
                correction = (np.linalg.pinv(np.nan_to_num(normal)) @ np.nan_to_num(rhs))[:, :, 0]
            state = state + np.where(np.isfinite(correction), correction, 0.0)
        raise AssertionError("unreachable")

    def error(self, theta: np.ndarray, iterations: int = 1) -> float:
        """The runs' position error, RMS per coordinate relative to its motion, pooled
        (root mean square over the coordinates)."""
        rms = np.sqrt(np.mean(self.residuals(theta, iterations) ** 2, axis=(0, 1)))
        return float(np.sqrt(np.mean((rms / self.motion) ** 2)))


def linearized_over(dynamics: Dynamics, log: ModelLog, theta: np.ndarray) -> np.ndarray:
    """The model's state matrices at (up to 2000) states of the log."""
    take = slice(None, None, max(1, log.samples // 2000))
    qd = reference_velocity(log)
    u = log.inputs[take] if log.inputs.shape[1] else np.empty((len(log.q[take]), 0))
    return linearized(dynamics, theta, log.q[take], qd[take], u)


def parts_for(dynamics: Dynamics, log: ModelLog, theta: np.ndarray) -> int:
    """Sub-steps per sample for the model's fastest mode over the log."""
    return substeps(linearized_over(dynamics, log, theta), log.step)


def simulation_error(model: Model, log: ModelLog, theta: np.ndarray) -> dict[str, Any]:
    """The free run of the model over the whole log from its measured initial state."""
    dynamics = Dynamics(model)
    parts = parts_for(dynamics, log, theta)
    whole = PieceSimulator(dynamics, log, Pieces(np.array([0]), log.samples), parts)
    sim = whole.run(theta)
    diverged = int(sim.diverged[0])
    if diverged >= 0:  # a run that leaves the log has no error to speak of: none is given
        rms = relative = np.full(len(model.coordinates), math.nan)
    else:
        rms = np.sqrt(np.mean((sim.q[0] - log.q) ** 2, axis=0))
        relative = rms / np.where(motion_rms(log) > 0, motion_rms(log), math.inf)

    def number(x: float) -> float | None:
        return None if math.isnan(x) else float(x)
    return {
        "per_coordinate": {c: {"rms": number(rms[i]), "unit": model.units.get(c, ""),
                               "relative": number(relative[i])}
                           for i, c in enumerate(model.coordinates)},
        "pooled": number(float(np.sqrt(np.mean(relative ** 2)))),
        "diverged_at_s": None if diverged < 0 else float(log.t[diverged] - log.t[0]),
        "substeps": parts,
        "definition": "free run from the measured initial state driven by the measured "
                      "input (band-limited interpolation between samples, Runge-Kutta); RMS "
                      "of each coordinate's error, relative: over the RMS of its motion about its "
                      "mean; pooled: root mean square of the relative errors; null when the run "
                      "diverges (diverged_at_s)",
    }
