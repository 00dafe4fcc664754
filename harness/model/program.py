"""A model's regressor as a term program: the text form that the core reads
(fmu/src/core/term_program.h), so that one compiled observer serves every model file.

Each entry of ``Y theta = r`` (:attr:`Model.scaled_entries`, SI units, constants
substituted) becomes a postfix program over a shared constant pool; the core evaluates
it at every sample.  :func:`evaluate_program` runs the same C over a whole log through
the package's native library.
"""
from __future__ import annotations

import ctypes
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import sympy

from ..names import plain
from .expressions import ExpressionError
from .model import Model
from .units import si_factor

#: The core's ops (enum TpOp of term_program.h, in its order; a test holds them equal).
OPS = ("constant", "position", "velocity", "acceleration", "input",
       "add", "multiply", "power",
       "negate", "sin", "cos", "tan", "tanh", "exp", "log", "sign", "abs", "sqrt",
       "atan", "sinh", "cosh")
OP = {name: code for code, name in enumerate(OPS)}
#: The core's limits (term_program.h).
MAX_COORDINATES, MAX_INPUTS, MAX_PARAMETERS = 7, 7, 32
MAX_TOKENS, MAX_CONSTANTS, MAX_STACK = 4096, 512, 32
#: the longest parameter name the FMU's messages take, plus one (TP_NAME_SIZE)
NAME_SIZE = 32

_FUNCTIONS = {sympy.sin: "sin", sympy.cos: "cos", sympy.tan: "tan", sympy.tanh: "tanh",
              sympy.exp: "exp", sympy.log: "log", sympy.sign: "sign", sympy.Abs: "abs",
              sympy.atan: "atan", sympy.sinh: "sinh", sympy.cosh: "cosh"}


class ProgramError(ExpressionError):
    """The model cannot be expressed as a term program (too large, or a term the core
    cannot evaluate)."""


@dataclass
class _Compiler:
    variables: dict[sympy.Symbol, tuple[int, int]]
    constants: dict[float, int]
    tokens: int = 0

    def constant(self, value: float) -> tuple[int, int]:
        if not np.isfinite(value):
            raise ProgramError(f"the constant {value} is not finite")
        index = self.constants.setdefault(value, len(self.constants))
        if index >= MAX_CONSTANTS:
            raise ProgramError(f"more than {MAX_CONSTANTS} distinct constants")
        return OP["constant"], index

    def compile(self, expr: sympy.Expr) -> tuple[list[tuple[int, int]], int]:
        """Postfix (op, arg) pairs of ``expr`` and the deepest stack they need."""
        if expr.is_Number or isinstance(expr, sympy.NumberSymbol):
            return [self.constant(float(expr))], 1
        if isinstance(expr, sympy.Symbol):
            if expr not in self.variables:
                raise ProgramError(f"the name {expr} is neither measured nor a constant")
            return [self.variables[expr]], 1
        if isinstance(expr, sympy.Add | sympy.Mul):
            op = OP["add"] if isinstance(expr, sympy.Add) else OP["multiply"]
            code, depth = self.compile(expr.args[0])
            for arg in expr.args[1:]:
                more, more_depth = self.compile(arg)
                code += [*more, (op, 0)]
                depth = max(depth, 1 + more_depth)
            return code, depth
        if isinstance(expr, sympy.Pow):
            base, base_depth = self.compile(expr.base)
            exponent, exponent_depth = self.compile(expr.exp)
            return [*base, *exponent, (OP["power"], 0)], max(base_depth, 1 + exponent_depth)
        name = _FUNCTIONS.get(type(expr))
        if name is not None and len(expr.args) == 1:
            code, depth = self.compile(expr.args[0])
            return [*code, (OP[name], 0)], depth
        raise ProgramError(f"the term '{expr}' uses {type(expr).__name__}, which the FMU's "
                           f"core cannot evaluate")


def compile_program(model: Model) -> str:
    """The text form of ``model``'s regressor (term_program.h): one entry per Y_ik and r_i.
    Raises :class:`ProgramError` naming what exceeds the core's limits."""
    n, m, p = len(model.coordinates), len(model.inputs), len(model.parameters)
    for what, count, limit in (("coordinates", n, MAX_COORDINATES), ("inputs", m, MAX_INPUTS),
                               ("unknown parameters", p, MAX_PARAMETERS)):
        if count > limit:
            raise ProgramError(f"{count} {what}: an FMU takes at most {limit}")
    s = model.symbols
    variables: dict[sympy.Symbol, tuple[int, int]] = {}
    for i, c in enumerate(model.coordinates):
        variables[s.position[c]] = (OP["position"], i)
        variables[s.velocity[c]] = (OP["velocity"], i)
        variables[s.acceleration[c]] = (OP["acceleration"], i)
    for j, u in enumerate(model.inputs):
        variables[s.inputs[u]] = (OP["input"], j)
    compiler = _Compiler(variables, {})
    lines = []
    for i, row in enumerate(model.scaled_entries):
        for k, entry in enumerate(row):
            where = f"equation {i + 1}, " + (f"the term of {model.parameters[k].name}"
                                             if k < p else "its known part")
            try:
                code, depth = compiler.compile(sympy.sympify(entry))
            except ProgramError as error:
                raise ProgramError(f"{where}: {error}") from None
            if depth > MAX_STACK:
                raise ProgramError(f"{where} nests {depth} levels deep: the FMU's core takes "
                                   f"at most {MAX_STACK}")
            compiler.tokens += len(code)
            lines.append(f"entry {i} {k} {len(code)}  " + "  ".join(f"{o} {a}" for o, a in code))
    if compiler.tokens > MAX_TOKENS:
        raise ProgramError(f"the regressor compiles to {compiler.tokens} tokens: the FMU's "
                           f"core takes at most {MAX_TOKENS}")
    pool = " ".join(repr(value) for value in compiler.constants)
    si = [si_factor(q.unit) if model.units else 1.0 for q in model.parameters]
    header = ["sto-term-program 1", f"# {plain(Path(model.source).name)}", f"sizes {n} {m} {p}",
              f"constants {len(compiler.constants)} {pool}".rstrip(),
              "nominal " + " ".join(repr(float(q.nominal)) for q in model.parameters),
              "scale " + " ".join(repr(float(f)) for f in si),
              "coordinate_scale " + " ".join(
                  repr(si_factor(model.units[c]) if model.units else 1.0)
                  for c in model.coordinates)]
    if any(q.bounded for q in model.parameters):
        header.append("bounds " + " ".join(f"{q.lower!r} {q.upper!r}"
                                           for q in model.parameters))
    if all(len(q.name) < NAME_SIZE for q in model.parameters):  # for the FMU's messages
        header.append("names " + " ".join(q.name for q in model.parameters))
    return "\n".join(header + lines) + "\n"


def evaluate_program(text: str, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                     inputs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Y (samples, n, p) and r (samples, n) of a program's text over a log, by the core's C
    (the native library).  q, qd, qdd: (samples, n); inputs: (samples, m), SI units.
    Raises ProgramError with the core's message for a text it refuses."""
    from ..native_library import load_library

    function = load_library().sto_term_program_evaluate
    pointer = ctypes.POINTER(ctypes.c_double)
    function.argtypes = [ctypes.c_char_p, ctypes.c_size_t, ctypes.c_long, pointer, pointer,
                         pointer, pointer, pointer, pointer, ctypes.c_char_p, ctypes.c_size_t]
    function.restype = ctypes.c_int
    q, qd, qdd = (np.ascontiguousarray(a, dtype=float) for a in (q, qd, qdd))
    u = np.ascontiguousarray(inputs, dtype=float)
    sizes = re.search(r"^sizes (\d+) (\d+) (\d+)\s*$", text, re.MULTILINE)
    if sizes is None:
        raise ProgramError("term program: no 'sizes N M P' line")
    n, m, p = (int(v) for v in sizes.groups())
    samples = q.shape[0]
    for name, array, columns in (("q", q, n), ("qd", qd, n), ("qdd", qdd, n), ("inputs", u, m)):
        if array.shape != (samples, columns):
            raise ValueError(f"{name} must have shape ({samples}, {columns}), not {array.shape}")
    Y = np.zeros((samples, n, max(p, 1)))
    r = np.zeros((samples, n))
    error = ctypes.create_string_buffer(512)
    data = text.encode()

    def ptr(a: np.ndarray) -> ctypes._Pointer:
        return a.ctypes.data_as(pointer)

    status = function(data, len(data), samples, ptr(q), ptr(qd), ptr(qdd),
                      ptr(u if u.size else np.zeros(1)), ptr(Y), ptr(r), error, len(error))
    if status == -1:
        raise ProgramError(error.value.decode(errors="replace"))
    if status != 0:
        raise MemoryError("the native term program evaluation ran out of memory")
    return Y[:, :, :p], r


def simulate_program(text: str, theta: np.ndarray, q0: np.ndarray, qd0: np.ndarray,
                     u: np.ndarray, step: float, parts: int, limit: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Runs of a program's equations by the core's C (core/model_simulation.h): from q0, qd0
    (runs, n) with parameters theta (runs, p) and inputs u (runs, 2 parts (samples-1) + 1,
    m), in the model file's units; positions and velocities (runs, samples, n) and, per
    run, the sample where it left its start by more than ``limit`` (n,), or -1."""
    from ..native_library import load_library

    function = load_library().sto_term_program_simulate
    pointer = ctypes.POINTER(ctypes.c_double)
    function.argtypes = [ctypes.c_char_p, ctypes.c_size_t, ctypes.c_int, ctypes.c_long,
                         ctypes.c_int, ctypes.c_double, pointer, pointer, pointer, pointer,
                         pointer, pointer, pointer, ctypes.POINTER(ctypes.c_long),
                         ctypes.c_char_p, ctypes.c_size_t]
    function.restype = ctypes.c_int
    runs, n = q0.shape
    samples = (u.shape[1] - 1) // (2 * parts) + 1
    arrays = [np.ascontiguousarray(a, dtype=float) for a in (theta, q0, qd0, u, limit)]
    q = np.empty((runs, samples, n))
    qd = np.empty((runs, samples, n))
    diverged = np.empty(runs, dtype=ctypes.c_long)
    error = ctypes.create_string_buffer(512)
    data = text.encode()

    def ptr(a: np.ndarray) -> ctypes._Pointer:
        return a.ctypes.data_as(pointer)

    status = function(data, len(data), runs, samples, parts, step,
                      *(ptr(a if a.size else np.zeros(1)) for a in arrays), ptr(q), ptr(qd),
                      diverged.ctypes.data_as(ctypes.POINTER(ctypes.c_long)), error, len(error))
    if status == -1:
        raise ProgramError(error.value.decode(errors="replace"))
    if status != 0:
        raise MemoryError("the native simulation ran out of memory")
    return q, qd, diverged.astype(int)


def energy_check(text: str, theta: np.ndarray, q: np.ndarray, inputs: np.ndarray) -> np.ndarray:
    """Per state (q: (samples, n), inputs: (samples, m), the model file's units), whether the
    program's equations with parameters ``theta`` create energy near rest, by the core's C
    (core/model_damping.h, the model FMU's ``negative_damping``): 0, or 1 + the coordinate
    whose friction gives energy (-1 where an entry is not finite)."""
    from ..native_library import load_library

    function = load_library().sto_term_program_energy
    pointer = ctypes.POINTER(ctypes.c_double)
    function.argtypes = [ctypes.c_char_p, ctypes.c_size_t, ctypes.c_long, pointer, pointer,
                         pointer, ctypes.POINTER(ctypes.c_int), ctypes.c_char_p,
                         ctypes.c_size_t]
    function.restype = ctypes.c_int
    arrays = [np.ascontiguousarray(a, dtype=float) for a in (theta, q, inputs)]
    which = np.zeros(q.shape[0], dtype=ctypes.c_int)
    error = ctypes.create_string_buffer(512)
    data = text.encode()
    status = function(data, len(data), q.shape[0],
                      *(a.ctypes.data_as(pointer) if a.size else
                        np.zeros(1).ctypes.data_as(pointer) for a in arrays),
                      which.ctypes.data_as(ctypes.POINTER(ctypes.c_int)), error, len(error))
    if status == -1:
        raise ProgramError(error.value.decode(errors="replace"))
    if status != 0:
        raise MemoryError("the native energy check ran out of memory")
    return which.astype(int)
