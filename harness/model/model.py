"""The model a file declares: names, parameters, equations and their regressor."""
from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import sympy

from .expressions import Symbols
from .numeric import as_samples, compile_regressor, rms_columns, stack
from .units import si_factor

#: How a log's inputs act between their samples ([log] inputs): held until the next sample
#: (a digital controller's output: a zero-order hold, which delays them by half a
#: sample), or samples of a continuous signal.
INPUT_TIMINGS = ("held", "sampled")


@dataclass(frozen=True)
class Parameter:
    """An unknown to identify: its name, the nominal (first guess) value and its unit;
    ``optional``: identify may leave it out (at 0) when the log does not support it;
    ``lower``, ``upper``: the range the file declares (``positive = true``: [0, inf]), which
    every estimate keeps to."""

    name: str
    nominal: float
    unit: str = ""
    optional: bool = False
    lower: float = -math.inf
    upper: float = math.inf

    @property
    def bounded(self) -> bool:
        """The file declares a range for it."""
        return math.isfinite(self.lower) or math.isfinite(self.upper)


@dataclass(frozen=True)
class Constant:
    """A known value of the equations: ``g = 9.81`` (dimensionless) or
    ``g = { value = 9.81, unit = "m/s^2" }``."""

    name: str
    value: float
    unit: str = ""


@dataclass(frozen=True)
class Equation:
    """One equation of motion, ``lhs = rhs``, and its regressor form
    ``sum_k theta_k * terms[k] = known`` (``terms`` has one entry per model parameter,
    0 where the parameter does not occur; constants stay symbolic)."""

    text: str
    lhs: sympy.Expr
    rhs: sympy.Expr
    terms: tuple[sympy.Expr, ...]
    known: sympy.Expr

    @property
    def residual(self) -> sympy.Expr:
        """``lhs - rhs``, zero on the model's trajectories."""
        return self.lhs - self.rhs


@dataclass(frozen=True)
class Model:
    """A model file, read and checked (see :func:`harness.model.read_model`).

    With ``units`` given, the numeric regressor works in SI base units: each coordinate,
    input and constant is scaled by its unit's SI factor, each parameter column by its
    unit's, so ``Y @ theta = r`` holds with theta in the units of the file.
    """

    source: str
    coordinates: tuple[str, ...]
    inputs: tuple[str, ...]
    parameters: tuple[Parameter, ...]
    constants: tuple[Constant, ...]
    units: Mapping[str, str]
    columns: Mapping[str, str]
    equations: tuple[Equation, ...]
    symbols: Symbols = field(repr=False)
    time_unit: str | None = None  # the log's time column's unit ([units] t; None: s)
    sample_rate: float | None = None  # [log] sample_rate [Hz]: no time column read
    input_timing: str | None = None   # [log] inputs, one of INPUT_TIMINGS (None: by data)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """The unknowns' names, in the order of the regressor's columns."""
        return tuple(p.name for p in self.parameters)

    @property
    def parameter_units(self) -> dict[str, str]:
        """Each parameter's unit as the file writes it ("" when it gives none)."""
        return {p.name: p.unit for p in self.parameters}

    @property
    def nominal(self) -> np.ndarray:
        """The parameters' nominal values, in the order of the regressor's columns."""
        return np.array([p.nominal for p in self.parameters], dtype=float)

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The declared ranges, lower and upper ends in the order of the regressor's columns
        (-inf, inf where a parameter has none)."""
        return (np.array([p.lower for p in self.parameters], dtype=float),
                np.array([p.upper for p in self.parameters], dtype=float))

    @cached_property
    def coulomb_coordinates(self) -> tuple[tuple[int, ...], ...]:
        """Per equation, the coordinates whose velocity enters it inside ``sign()``
        (Coulomb friction): the equation holds only where they move
        (:mod:`harness.model.friction_rows`)."""
        velocity = list(self.symbols.velocity.values())
        out = []
        for eq in self.equations:
            inside = set().union(*(f.free_symbols for f in eq.residual.atoms(sympy.sign)))
            out.append(tuple(k for k, v in enumerate(velocity) if v in inside))
        return tuple(out)

    @cached_property
    def _scales(self) -> tuple[dict[sympy.Symbol, float], np.ndarray]:
        """SI factors of the measured names and constants, and of the parameter columns."""
        if not self.units:
            return {}, np.ones(len(self.parameters))
        s = self.symbols
        factors: dict[sympy.Symbol, float] = {}
        for c in self.coordinates:
            for table in (s.position, s.velocity, s.acceleration):
                factors[table[c]] = si_factor(self.units[c])  # per s, per s^2: factor 1
        for u in self.inputs:
            factors[s.inputs[u]] = si_factor(self.units[u])
        for k in self.constants:
            factors[s.constants[k.name]] = si_factor(k.unit)
        return factors, np.array([si_factor(p.unit) for p in self.parameters])

    @cached_property
    def scaled_entries(self) -> tuple[tuple[sympy.Expr, ...], ...]:
        """Per equation, its regressor entries ``Y_i1 .. Y_ip`` then ``r_i`` as expressions of
        the measured symbols (positions, velocities, accelerations, inputs) in SI units, the
        constants substituted and each parameter column scaled to the file's unit: the
        numbers of :meth:`regressor`, and what the term program compiles."""
        factors, column_scales = self._scales
        s = self.symbols
        values = {s.constants[k.name]: sympy.Float(k.value) * factors.get(s.constants[k.name], 1.0)
                  for k in self.constants}
        scaled = {sym: sym * f for sym, f in factors.items() if sym not in values and f != 1.0}
        rows = []
        for eq in self.equations:
            terms = [term.subs(values).xreplace(scaled) * (sympy.Float(c) if c != 1.0 else 1)
                     for term, c in zip(eq.terms, column_scales)]
            rows.append((*terms, eq.known.subs(values).xreplace(scaled)))
        return tuple(rows)

    @cached_property
    def _evaluate(self) -> Callable[..., list]:
        entries = [entry for row in self.scaled_entries for entry in row]
        return compile_regressor(self.symbols.measured(), entries)

    def regressor(self, q: object, qd: object, qdd: object,
                  inputs: object = None) -> tuple[np.ndarray, np.ndarray]:
        """The equations as ``Y @ theta = r`` at every sample.

        q, qd, qdd: positions, velocities, accelerations, shape (samples, n_coordinates)
        (or (samples,) for one coordinate); inputs: shape (samples, n_inputs), in the order
        of ``self.inputs``. Returns Y (samples, n_equations, n_parameters) and
        r (samples, n_equations).
        """
        n, m = len(self.coordinates), len(self.inputs)
        q, qd, qdd = (as_samples(a, n, name) for a, name in ((q, "q"), (qd, "qd"), (qdd, "qdd")))
        u = as_samples(inputs, m, "inputs")
        samples = q.shape[0]
        if not (qd.shape[0] == qdd.shape[0] == samples and (m == 0 or u.shape[0] == samples)):
            raise ValueError("q, qd, qdd and inputs must have the same number of samples")
        columns = [*q.T, *qd.T, *qdd.T, *u.T]
        flat = stack(self._evaluate(*columns), samples)
        p = len(self.parameters)
        flat = flat.reshape(samples, len(self.equations), p + 1)
        return np.ascontiguousarray(flat[:, :, :p]), np.ascontiguousarray(flat[:, :, p])

    def column_scales(self, q: object, qd: object, qdd: object,
                      inputs: object = None) -> np.ndarray:
        """Each parameter's regressor column scale over a log (RMS, see
        :func:`harness.model.numeric.rms_columns`), in the order of ``self.parameters``:
        the yardstick that makes a regularization relative to each column."""
        Y, _ = self.regressor(q, qd, qdd, inputs)
        return rms_columns(Y)

    def residuals(self, theta: object, q: object, qd: object, qdd: object,
                  inputs: object = None) -> np.ndarray:
        """``Y theta - r`` at every sample, shape (samples, n_equations)."""
        Y, r = self.regressor(q, qd, qdd, inputs)
        return Y @ np.asarray(theta, dtype=float) - r

    def column(self, name: str) -> str:
        """The log column that holds ``name`` (a coordinate, an input or t)."""
        return self.columns[name]
