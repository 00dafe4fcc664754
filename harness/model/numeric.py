"""Numbers from the symbolic regressor: Y and r over many samples at once (numpy).

sympy is imported where a model's expressions are compiled, not with the module: the
robot path and the least squares (rms_columns) use none of it, and sympy costs about
0.8 s to import."""
from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import sympy


def compile_numpy(arguments: Sequence[sympy.Symbol],
                  expressions: sympy.Expr | Sequence[sympy.Expr]) -> Callable[..., Any]:
    """A numpy function of ``arguments`` (arrays of one shape) returning ``expressions``
    (one, or a list): every numeric function of a model's symbols is made here.

    cse shares subexpressions (sign(der(x)), sin(q), ...) between the entries.  The
    generated code holds no name of the model's: dummify names the arguments _Dummy_N, and
    the constants (E, pi), which numpy's printer writes as the bare names e and pi that
    lambdify also binds to the model's symbols of those names, are written as numbers."""
    import sympy
    items = [expressions] if isinstance(expressions, sympy.Basic) else list(expressions)
    constants: set[sympy.Basic] = set()
    for item in items:
        constants |= sympy.sympify(item).atoms(sympy.NumberSymbol)
    values = {c: sympy.Float(float(c)) for c in constants}
    items = [sympy.sympify(item).xreplace(values) for item in items]
    return sympy.lambdify(list(arguments),
                          items[0] if isinstance(expressions, sympy.Basic) else items,
                          modules="numpy", cse=True, dummify=True)


def compile_regressor(arguments: Sequence[sympy.Symbol],
                      entries: Sequence[sympy.Expr]) -> Callable[..., list]:
    """A numpy function of ``arguments`` (arrays of one shape) returning ``entries``."""
    return compile_numpy(arguments, list(entries))


def as_samples(values: object, count: int, what: str) -> np.ndarray:
    """``values`` as a float array (samples, count); a 1-D array is the samples of a single
    name when ``count`` is 1."""
    if values is None and count == 0:  # a model without inputs
        return np.empty((0, 0))
    array = np.asarray(values, dtype=float)
    if array.ndim == 1 and count == 1:
        array = array[:, None]
    if array.ndim != 2 or array.shape[1] != count:
        raise ValueError(f"{what} must have shape (samples, {count}), not {array.shape}")
    return array


def stack(values: Sequence[object], samples: int) -> np.ndarray:
    """The entries lambdify returned (arrays, or plain numbers for constant entries) as an
    array (samples, len(values))."""
    out = np.empty((samples, len(values)))
    for k, value in enumerate(values):
        out[:, k] = np.broadcast_to(np.asarray(value, dtype=float), (samples,))
    return out


def rms_columns(Y: np.ndarray) -> np.ndarray:
    """Scale of each parameter's regressor column: sqrt(mean over samples of the squared
    column, summed over the equations), i.e. sqrt(diag(Y'Y) / samples)."""
    if Y.shape[0] == 0:
        raise ValueError("no samples to take the column scales from")
    return np.sqrt(np.einsum("sik,sik->k", Y, Y) / Y.shape[0])
