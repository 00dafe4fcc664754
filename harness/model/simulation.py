"""A model file's equations simulated: the machine driven by its measured input.

The equations are affine in the accelerations (the reader checks it), so for given
parameter values they read ``M(q, theta) q'' = -h(q, q', u, theta)`` (SI, one equation
per coordinate). :class:`Dynamics` compiles M and h once with the parameters as
arguments; :func:`simulate` integrates many independent runs at once (classical
Runge-Kutta, several sub-steps per sample, the input between its samples by its
band-limited (Fourier) interpolant): what the scores, the cross-validation and the
output-error refinement all use. The runs are the core's C (core/model_simulation.c,
through the term program of the model's FMU); a model beyond the term program's limits
runs the same scheme in numpy.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
import scipy.signal
import sympy

from .model import Model
from .numeric import compile_numpy
from .program import ProgramError, compile_program, simulate_program

#: A sub-step is at most this fraction of the fastest linearized period's radian
#: (|lambda| h <= 0.3: Runge-Kutta's phase error below 1e-5 per sub-step).
STABLE_FRACTION = 0.3
#: ... and at most this many sub-steps per sample.
MOST_SUBSTEPS = 16
#: A run whose position leaves this many times the log's range (or turns non-finite)
#: has diverged; it is stopped there.
DIVERGED = 1e3


@dataclass(frozen=True)
class Run:
    """Simulated positions (runs, samples, coordinates) in the file's units; ``diverged``
    per run: the index of the first sample where it diverged, or -1."""

    q: np.ndarray
    qd: np.ndarray
    diverged: np.ndarray


class Dynamics:
    """q'' = f(q, q', u; theta) of a model, in the file's units."""

    def __init__(self, model: Model) -> None:
        self.model = model  # one equation per coordinate, affine in the accelerations
        s = model.symbols
        self._q = list(s.position.values())
        self._qd = list(s.velocity.values())
        self._qdd = list(s.acceleration.values())
        self._u = list(s.inputs.values())
        # Dummy: a symbol no name of the file can equal (a coordinate named theta_0 would
        # be the same sympy symbol as a Symbol("theta_0"))
        self._theta = [sympy.Dummy(f"theta_{k}", real=True) for k in range(len(model.parameters))]

    @cached_property
    def _symbolic(self) -> tuple[list[list[sympy.Expr]], list[sympy.Expr], list[sympy.Symbol]]:
        """M (rows of the accelerations' coefficients), h, and the compiled functions'
        arguments."""
        residuals = [sum((theta * term for theta, term in zip(self._theta, row[:-1])),
                         sympy.Integer(0)) - row[-1] for row in self.model.scaled_entries]
        at_rest = {a: 0 for a in self._qdd}
        mass = [[sympy.diff(e, a) for a in self._qdd] for e in residuals]
        bias = [e.xreplace(at_rest) for e in residuals]
        return mass, bias, [*self._q, *self._qd, *self._u, *self._theta]

    @cached_property
    def _compiled(self) -> Callable[..., Any]:
        """numpy: q'' itself for one coordinate, else M's entries then h."""
        mass, bias, arguments = self._symbolic
        if len(self._q) == 1:
            return compile_numpy(arguments, -bias[0] / mass[0][0])
        return compile_numpy(arguments, [*(m for row in mass for m in row), *bias])

    @cached_property
    def program(self) -> str | None:
        """The model as a term program, which the core's C simulates (None: the model
        exceeds the core's limits, and numpy simulates it)."""
        try:
            return compile_program(self.model)
        except ProgramError:
            return None

    def __call__(self, q: np.ndarray, qd: np.ndarray, u: np.ndarray, theta: np.ndarray
                 ) -> np.ndarray:
        """Accelerations (runs, n) at positions and velocities (runs, n) and inputs
        (runs, m), for parameters theta (p,) or per run (runs, p). The positions and
        velocities are in the file's units (the SI scaling lives in the compiled terms,
        and acceleration columns are scaled like the positions)."""
        with np.errstate(all="ignore"):
            return self.accelerations(q, qd, u, self.columns(theta, q.shape[0]))

    def columns(self, theta: np.ndarray, runs: int) -> list[np.ndarray]:
        """theta as the compiled function takes it: one array (runs,) per parameter."""
        return list(np.broadcast_to(theta, (runs, len(self._theta))).T)

    def accelerations(self, q: np.ndarray, qd: np.ndarray, u: np.ndarray,
                      theta: list[np.ndarray]) -> np.ndarray:
        """:meth:`__call__` with theta from :meth:`columns` (the inner loop's form; the
        caller sets numpy's error state)."""
        runs, n = q.shape
        values = self._compiled(*q.T, *qd.T, *u.T, *theta)
        if n == 1:
            out = np.empty((runs, 1))
            out[:, 0] = values
            return out
        mass = np.empty((runs, n, n))
        bias = np.empty((runs, n, 1))
        for k in range(n * n):
            mass[:, k // n, k % n] = values[k]
        for k in range(n):
            bias[:, k, 0] = values[n * n + k]
        try:
            return -np.linalg.solve(mass, bias)[:, :, 0]
        except np.linalg.LinAlgError:
            return np.full((runs, n), np.nan)


def linearized(dynamics: Dynamics, theta: np.ndarray, q: np.ndarray, qd: np.ndarray,
               u: np.ndarray) -> np.ndarray:
    """The state matrices [[0, I], [dq''/dq, dq''/dq']] at the given states (samples, n),
    by forward differences; rows where the model is not finite are dropped."""
    samples, n = q.shape
    base = dynamics(q, qd, u, theta)
    A = np.zeros((samples, 2 * n, 2 * n))
    A[:, :n, n:] = np.eye(n)
    for which in (0, 1):
        for j in range(n):
            scale = float(np.max(np.abs((q, qd)[which][:, j])))
            delta = 1e-6 * (scale if scale > 0 else 1.0)
            moved = [q.copy(), qd.copy()]
            moved[which][:, j] += delta
            with np.errstate(all="ignore"):
                A[:, n:, which * n + j] = (dynamics(moved[0], moved[1], u, theta) - base) / delta
    return A[np.all(np.isfinite(A), axis=(1, 2))]


def substeps(A: np.ndarray, step: float) -> int:
    """Sub-steps per sample so that the fastest mode of the state matrices A satisfies
    |lambda| h <= STABLE_FRACTION."""
    if not len(A):
        return 1
    fastest = float(np.max(np.abs(np.linalg.eigvals(A))))
    needed = math.ceil(fastest * step / STABLE_FRACTION) if math.isfinite(fastest) else 1
    return int(min(max(needed, 1), MOST_SUBSTEPS))


def time_constant(A: np.ndarray) -> float:
    """The slowest decay time [s] of the state matrices' modes that decay or grow (the
    median over the states of 1 / the smallest nonzero |Re lambda|); inf for a model
    without such modes."""
    if not len(A):
        return math.inf
    eig = np.linalg.eigvals(A)
    rates = np.abs(eig.real)
    scale = np.max(np.abs(eig), axis=1, keepdims=True)
    rates = np.where(rates > 1e-9 * scale, rates, np.inf).min(axis=1)
    finite = rates[np.isfinite(rates)]
    return float(1.0 / np.median(finite)) if len(finite) else math.inf


def input_at(u: np.ndarray, step: float, parts: int) -> np.ndarray:
    """The inputs (samples, m) at every 1/(2 parts) of a sampling step from the first sample
    to the last (shape (2 parts (samples-1) + 1, m)): band-limited interpolation (Fourier,
    the log mirrored at its ends so that they join), exact for an input sampled above
    twice its bandwidth, where a spline loses a percent of a signal at a quarter of the
    sample rate."""
    samples = u.shape[0]
    needed = 2 * parts * (samples - 1) + 1
    if u.shape[1] == 0:
        return np.empty((needed, 0))
    extended = np.concatenate([u, u[::-1]], axis=0)
    fine = scipy.signal.resample(extended, 2 * parts * extended.shape[0], axis=0)
    return fine[:needed]


def simulate(dynamics: Dynamics, theta: np.ndarray, q0: np.ndarray, qd0: np.ndarray,
             u: np.ndarray, step: float, parts: int, span: np.ndarray) -> Run:
    """Runs from the states q0, qd0 (runs, n), each driven by its input u (runs, samples,
    m), sampled at ``step``, integrated with ``parts`` Runge-Kutta sub-steps per sample
    (u given at every half sub-step, shape (runs, 2 parts (samples-1) + 1, m)). A run whose
    position leaves its start by DIVERGED times ``span`` (per coordinate: the log's range)
    is stopped and marked."""
    runs, n = q0.shape
    limit = DIVERGED * np.broadcast_to(span, (n,))
    if dynamics.program is not None:
        q, qd, diverged = simulate_program(
            dynamics.program, np.broadcast_to(theta, (runs, len(dynamics.model.parameters))),
            q0, qd0, u, step, parts, limit)
        return Run(q, qd, diverged)
    f, theta_columns = dynamics.accelerations, dynamics.columns(theta, runs)
    samples = (u.shape[1] - 1) // (2 * parts) + 1
    h = step / parts
    q_out = np.empty((runs, samples, n))
    qd_out = np.empty((runs, samples, n))
    q, qd = q0.astype(float).copy(), qd0.astype(float).copy()
    diverged = np.full(runs, -1)
    q_out[:, 0], qd_out[:, 0] = q, qd
    with np.errstate(all="ignore"):
        _integrate(f, theta_columns, q, qd, q0, u, h, parts, limit, q_out, qd_out, diverged)
    return Run(q_out, qd_out, diverged)


def _integrate(f: Callable[..., np.ndarray], theta: list[np.ndarray], q: np.ndarray,
               qd: np.ndarray, q0: np.ndarray, u: np.ndarray, h: float, parts: int,
               limit: np.ndarray, q_out: np.ndarray, qd_out: np.ndarray,
               diverged: np.ndarray) -> None:
    """:func:`simulate`'s loop in numpy (a model beyond the term program's limits),
    filling q_out, qd_out and diverged; the same scheme as core/model_simulation.c."""
    half, sixth = 0.5 * h, h / 6
    for k in range(1, q_out.shape[1]):
        for j in range(parts):
            i = 2 * ((k - 1) * parts + j)
            um = u[:, i + 1]
            a1 = f(q, qd, u[:, i], theta)
            v2 = qd + half * a1
            a2 = f(q + half * qd, v2, um, theta)
            v3 = qd + half * a2
            a3 = f(q + half * v2, v3, um, theta)
            v4 = qd + h * a3
            a4 = f(q + h * v3, v4, u[:, i + 2], theta)
            q = q + sixth * (qd + 2 * (v2 + v3) + v4)
            qd = qd + sixth * (a1 + 2 * (a2 + a3) + a4)
        bad = ~np.all(np.isfinite(q) & np.isfinite(qd) & (np.abs(q - q0) <= limit), axis=1)
        if bad.any():  # held where it left, so that it does not overflow
            diverged[bad & (diverged < 0)] = k
            q[bad], qd[bad] = q_out[bad, k - 1], qd_out[bad, k - 1]
        q_out[:, k], qd_out[:, k] = q, qd
