"""Output-error refinement: from the least-squares estimate, the parameters that make the
model's simulation follow the measured positions.

Least squares on derivatives (IDIM-LS) minimize the equation error, whose regressors carry
the noise and the lag of the differentiation; the output error has neither. The log is
cut into short runs (multiple shooting without continuity: each run starts from its own
initial state, an unknown beside the parameters), so that a lightly damped or unstable
model cannot wander off over the whole log. The unknowns are found by
``scipy.optimize.least_squares`` (trust region, sparse Jacobian by finite differences);
the parameters' standard errors are the sandwich over the runs of the Jacobian with the
initial states profiled out, which holds when the residuals within a run are correlated.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.optimize
import scipy.sparse

from .log import ModelLog
from .model import Model
from .scores import PieceSimulator, linearized_over, pieces
from .simulation import Dynamics, simulate, substeps, time_constant
from .zero_phase import Regression

#: Runs last this many of the model's slowest time constants (long enough for the
#: damping and friction to act, short enough that a drift cannot build up), within
#: RUN_SAMPLES samples and a tenth of the log; at most MOST_RUNS of them.
RUN_TIME_CONSTANTS = 2.0
RUN_SAMPLES = (20, 2000)
MOST_RUNS = 160
#: The solver's stopping tolerances (relative change of the cost and of the unknowns: a
#: parameter then moves by less than 1e-6 of itself, a hundredth of a standard error).
TOLERANCE = 1e-6
MAX_EVALUATIONS = 60
#: The forward differences' step, relative to the scaled unknowns.
FD_STEP = 1e-6
#: Gauss-Newton steps of the held-out runs' initial states in the refinement's check (the
#: two estimates differ little: their scores need the states' fit converged).
CHECK_ITERATIONS = 4


@dataclass(frozen=True)
class Refinement:
    """The output-error estimate and how it was found."""

    theta: np.ndarray
    std_error: np.ndarray
    cost_start: float      # relative RMS position error of the runs, from the start values
    cost_end: float        # ... at the estimate
    evaluations: int
    status: str


def run_length(log: ModelLog, time_constant: float) -> int:
    """Samples per run: RUN_TIME_CONSTANTS time constants, within RUN_SAMPLES and a tenth
    of the log."""
    wanted = RUN_TIME_CONSTANTS * time_constant / log.step
    length = int(np.clip(round(wanted) if math.isfinite(wanted) else RUN_SAMPLES[1],
                         *RUN_SAMPLES))
    return max(min(length, log.samples // 10), 8)


def refine(model: Model, log: ModelLog, theta: np.ndarray, first: int = 0,
           last: int | None = None, dynamics: Dynamics | None = None,
           most_runs: int = MOST_RUNS, free: np.ndarray | None = None) -> Refinement:
    """The output-error parameters over samples [first, last) of ``log``, from ``theta``,
    on at most ``most_runs`` runs; only the unknowns ``free`` (a mask; None: all) move,
    the others keep their values in ``theta`` (standard error 0)."""
    dynamics = dynamics or Dynamics(model)
    last = log.samples if last is None else last
    A = linearized_over(dynamics, log, theta)
    length = run_length(log, time_constant(A))
    runs = pieces(first, last, length, most_runs)
    if len(runs.starts) < 2:
        raise ValueError(f"{log.source}: too short for the output-error refinement's runs")
    parts = substeps(A, log.step)
    free = np.ones(len(theta), dtype=bool) if free is None else free
    problem = _Problem(PieceSimulator(dynamics, log, runs, parts), theta, free)
    start = problem.start_vector()
    cost_start = problem.relative_error(start)
    result = scipy.optimize.least_squares(
        problem.residuals, start, jac=problem.jacobian, method="trf", tr_solver="lsmr",
        bounds=problem.box(model.bounds), xtol=TOLERANCE, ftol=TOLERANCE, gtol=TOLERANCE,
        max_nfev=MAX_EVALUATIONS)
    theta_end = problem.theta(result.x)
    std = problem.std_error(result.x)
    return Refinement(theta_end, std, cost_start, problem.relative_error(result.x),
                      int(result.nfev), str(result.message))


class _Problem:
    """The unknowns [parameters / their scales, run states / their scales] and the
    residuals [(simulated - measured) / motion RMS] of every run's samples."""

    def __init__(self, simulator: PieceSimulator, theta: np.ndarray, free: np.ndarray) -> None:
        self.sim = simulator
        self.runs, self.length, self.n = simulator.measured.shape
        self.free = np.flatnonzero(free)
        self.p = len(self.free)    # the unknowns that move
        self.theta_scale = np.where(np.abs(theta) > 0, np.abs(theta), 1.0)[self.free]
        velocity = np.sqrt(np.mean(simulator.qd0 ** 2, axis=0))
        self.state_scale = np.concatenate([simulator.motion,
                                           np.where(velocity > 0, velocity, 1.0)])
        self.theta0 = np.asarray(theta, float)

    def start_vector(self) -> np.ndarray:
        states = np.concatenate([self.sim.q0, self.sim.qd0], axis=1) / self.state_scale
        return np.concatenate([self.theta0[self.free] / self.theta_scale, states.ravel()])

    def box(self, bounds: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """The declared ranges of the free unknowns in the scaled unknowns (the run states
        are free)."""
        lower, upper = bounds
        states = np.full(self.runs * 2 * self.n, np.inf)
        return (np.concatenate([lower[self.free] / self.theta_scale, -states]),
                np.concatenate([upper[self.free] / self.theta_scale, states]))

    def theta(self, x: np.ndarray) -> np.ndarray:
        """Every parameter: the free ones from x, the others as they started."""
        out = self.theta0.copy()
        out[self.free] = x[:self.p] * self.theta_scale
        return out

    def _states(self, x: np.ndarray) -> np.ndarray:
        return x[self.p:].reshape(self.runs, 2 * self.n) * self.state_scale

    def _simulate(self, thetas: np.ndarray, states: np.ndarray, copies: int) -> np.ndarray:
        """Positions (copies, runs, length n) of ``copies`` sets of every run."""
        with np.errstate(all="ignore"):
            run = simulate(self.sim.dynamics, thetas, states[:, :self.n], states[:, self.n:],
                           np.concatenate([self.sim.u] * copies), self.sim.log.step,
                           self.sim.parts, self.sim.span)
        q = run.q / self.sim.motion
        return q.reshape(copies, self.runs, self.length * self.n)

    def _measured(self) -> np.ndarray:
        return (self.sim.measured / self.sim.motion).reshape(self.runs, -1)

    def residuals(self, x: np.ndarray) -> np.ndarray:
        theta = np.broadcast_to(self.theta(x), (self.runs, len(self.theta0)))
        q = self._simulate(theta, self._states(x), 1)[0]
        out = (q - self._measured()).ravel()
        return np.where(np.isfinite(out), out, 1e6)

    def relative_error(self, x: np.ndarray) -> float:
        e = self.residuals(x).reshape(self.runs, self.length, self.n)
        return float(np.sqrt(np.mean(np.mean(e ** 2, axis=(0, 1)))))

    def _blocks(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Residuals (runs, L n) and the Jacobian's blocks by forward differences:
        parameters (runs, L n, p) and each run's own state (runs, L n, 2n)."""
        theta, states = self.theta(x), self._states(x)
        k = self.p + 2 * self.n
        steps = FD_STEP * np.maximum(np.abs(x[:self.p]), 1.0)
        thetas = [np.broadcast_to(theta, (self.runs, len(theta)))]
        starts = [states]
        for j, which in enumerate(self.free):
            moved = theta.copy()
            moved[which] += steps[j] * self.theta_scale[j]
            thetas.append(np.broadcast_to(moved, (self.runs, len(theta))))
            starts.append(states)
        state_step = FD_STEP
        for j in range(2 * self.n):
            moved = states.copy()
            moved[:, j] += state_step * self.state_scale[j]
            thetas.append(thetas[0])
            starts.append(moved)
        q = self._simulate(np.concatenate(thetas), np.concatenate(starts), k + 1)
        residual = q[0] - self._measured()
        d_theta = np.stack([(q[1 + j] - q[0]) / steps[j] for j in range(self.p)], axis=2)
        d_state = np.stack([(q[1 + self.p + j] - q[0]) / state_step
                            for j in range(2 * self.n)], axis=2)
        return residual, d_theta, d_state

    def jacobian(self, x: np.ndarray) -> scipy.sparse.csr_matrix:
        _, d_theta, d_state = self._blocks(x)
        rows = self.runs * self.length * self.n
        dense_theta = d_theta.reshape(rows, self.p)
        m = self.length * self.n
        row_index = np.repeat(np.arange(rows), 2 * self.n)
        column_index = (self.p + np.repeat(np.arange(self.runs), m * 2 * self.n) * 2 * self.n
                        + np.tile(np.arange(2 * self.n), rows))
        states = scipy.sparse.csr_matrix((np.nan_to_num(d_state.ravel(), posinf=0, neginf=0),
                                          (row_index, column_index)),
                                         shape=(rows, self.p + 2 * self.n * self.runs))
        parameters = scipy.sparse.csr_matrix(np.nan_to_num(dense_theta, posinf=0, neginf=0))
        parameters.resize(rows, self.p + 2 * self.n * self.runs)
        return (parameters + states).tocsr()

    def std_error(self, x: np.ndarray) -> np.ndarray:
        """Sandwich over the runs with each run's state profiled out, in the parameters'
        units (1 sigma)."""
        residual, d_theta, d_state = self._blocks(x)
        normal = np.einsum("rsi,rsj->rij", d_state, d_state)
        normal += 1e-12 * np.einsum("rii->r", normal)[:, None, None] * np.eye(2 * self.n)
        cross = np.einsum("rsi,rsj->rij", d_state, d_theta)
        projected = d_theta - np.einsum("rsi,rij->rsj", d_state, np.linalg.solve(normal, cross))
        H = np.einsum("rsi,rsj->ij", projected, projected)
        scores = np.einsum("rsi,rs->ri", projected, residual)
        S = scores.T @ scores * self.runs / max(self.runs - self.p, 1)
        out = np.zeros(len(self.theta0))
        try:
            H_inv = np.linalg.inv(H)
        except np.linalg.LinAlgError:
            out[self.free] = math.inf
            return out
        variance = np.diag(H_inv @ S @ H_inv)
        out[self.free] = np.sqrt(np.maximum(variance, 0.0)) * self.theta_scale
        return out



@dataclass(frozen=True)
class RefinementCheck:
    """Least squares against refinement on held-out halves of the log: each half's
    estimates scored by simulation on the other half (runs from fitted initial states)."""

    least_squares_halves: np.ndarray   # held-out relative position error, per half (2,)
    refined_halves_error: np.ndarray
    refined_halves: np.ndarray   # each half's refined estimate (2, p)

    @property
    def least_squares(self) -> float:
        return float(np.mean(self.least_squares_halves))

    @property
    def refined(self) -> float:
        return float(np.mean(self.refined_halves_error))

    @property
    def ratio(self) -> float:
        """The refined error over least squares', the geometric mean of the two halves'
        ratios: each half counts by its relative change, whatever its error level, so that
        one half's large errors cannot outvote the other (on a coarse log with Coulomb
        friction a refinement can win one half by much and lose the other by more)."""
        with np.errstate(all="ignore"):  # nan when undefined (0/0, inf/inf): no win
            return float(np.exp(np.mean(np.log(self.refined_halves_error
                                               / self.least_squares_halves))))

    @property
    def improves(self) -> bool:
        return self.ratio < 1.0

    def as_dict(self) -> dict[str, Any]:
        return {"least_squares": self.least_squares, "refined": self.refined,
                "ratio": self.ratio,
                "per_half": {"least_squares": self.least_squares_halves.tolist(),
                             "refined": self.refined_halves_error.tolist()}}

    def start(self) -> np.ndarray:
        """Where the refinement over the whole log starts: the halves' mean."""
        return np.mean(self.refined_halves, axis=0)

    def spread(self) -> np.ndarray:
        """The refined estimate's standard error as the two halves tell it: half their
        difference (two independent halves of spread s each: the whole log's is
        s / sqrt(2), and their difference's mean square is 2 s^2). One degree of freedom,
        but it sees what the sandwich cannot: a misfit of the model (Coulomb friction
        through a sticking joint, coarse encoder steps) that moves the estimate with the
        data; on the two-link arm's 0.01 rad logs the halves differed by up to 2700 of
        the sandwich's errors."""
        return np.abs(self.refined_halves[0] - self.refined_halves[1]) / 2.0


def check_on_halves(model: Model, log: ModelLog, rows: Regression, theta: np.ndarray,
                    dynamics: Dynamics | None = None, free: np.ndarray | None = None
                    ) -> RefinementCheck:
    """Fit least squares on the regressor ``rows`` of one half of the log, refine it on that
    half, and score both on the other half; the scores averaged over the two halves. Only
    the unknowns ``free`` (None: all) are fitted; the others keep their values in
    ``theta``."""
    from .fit import estimate

    dynamics = dynamics or Dynamics(model)
    A = linearized_over(dynamics, log, theta)
    length, parts = run_length(log, time_constant(A)), substeps(A, log.step)
    middle = log.samples // 2
    halves = ((0, middle), (middle, log.samples))
    scores: dict[str, list[float]] = {"least_squares": [], "refined": []}
    refined_halves = []
    free = np.ones(len(theta), dtype=bool) if free is None else free
    lower, upper = model.bounds
    for k, (first, last) in enumerate(halves):
        mine = (rows.t >= log.t[first]) & (rows.t < log.t[last - 1])
        start = np.where(free, 0.0, theta)  # the others as given (0 or a range's end)
        known = rows.Y[mine][:, :, ~free] @ start[~free]
        start[free] = estimate(rows.Y[mine][:, :, free], rows.r[mine] - known,
                               model.nominal[free],
                               mask=None if rows.mask is None else rows.mask[mine],
                               bounds=(lower[free], upper[free]))
        refined = refine(model, log, start, first, last, dynamics, MOST_RUNS // 2,
                         free).theta
        refined_halves.append(refined)
        other_first, other_last = halves[1 - k]
        scorer = PieceSimulator(dynamics, log, pieces(other_first, other_last, length,
                                                      MOST_RUNS // 2), parts)
        scores["least_squares"].append(scorer.error(start, CHECK_ITERATIONS))
        scores["refined"].append(scorer.error(refined, CHECK_ITERATIONS))
    return RefinementCheck(np.array(scores["least_squares"]), np.array(scores["refined"]),
                           np.array(refined_halves))
