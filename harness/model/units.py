"""Units of a model file: each equation's dimensions checked with pint (the registry and
the unit strings are harness.units', shared with the log readers)."""
from __future__ import annotations

import math

import pint
import sympy

from ..units import quantity, registry, si_factor
from .expressions import ExpressionError

__all__ = ["check_equation", "quantity", "registry", "si_factor"]


def _dimension(expr: sympy.Expr, units: dict[sympy.Symbol, pint.Quantity]) -> pint.Quantity:
    """The unit of ``expr`` as a pint quantity of magnitude 1 (its dimension is what counts)."""
    one = registry().Quantity(1.0)
    if expr.is_Symbol:
        return units[expr]
    if expr.is_Number or expr is sympy.pi:
        return one
    if expr.is_Add:
        _same_dimension(list(expr.args), units, "a sum")
        return _dimension(expr.args[0], units)
    if expr.is_Mul:
        result = one
        for arg in expr.args:
            result = result * _dimension(arg, units)
        return result
    if expr.is_Pow:
        base, power = expr.args
        if not _dimension(power, units).dimensionless:
            raise ExpressionError(f"has an exponent with a dimension: '{power}'")
        base_unit = _dimension(base, units)
        if base_unit.dimensionless:
            return one
        if not power.is_Number:
            raise ExpressionError(f"raises '{base}' ({base_unit.dimensionality}) to the "
                                  f"non-numeric power '{power}'")
        exponent = float(power)
        if not math.isfinite(exponent):  # pint would work a power of inf out without end
            raise ExpressionError(f"raises '{base}' ({base_unit.dimensionality}) to the "
                                  f"power {power}, which is not a finite number")
        return base_unit ** exponent
    if isinstance(expr, (sympy.Abs,)):
        return _dimension(expr.args[0], units)
    if isinstance(expr, sympy.sign):
        _dimension(expr.args[0], units)  # any dimension: only its sign counts
        return one
    if isinstance(expr, sympy.Function):  # sin, cos, tanh, exp, log, ...
        inner = _dimension(expr.args[0], units)
        if not inner.dimensionless:
            raise ExpressionError(f"takes {expr.func.__name__} of '{expr.args[0]}', which has "
                                  f"the dimension {inner.dimensionality} (it must be "
                                  "dimensionless, e.g. an angle in rad)")
        return one
    raise ExpressionError(f"has a term '{expr}' whose unit cannot be worked out")


def _same_dimension(terms: list[sympy.Expr], units, where: str) -> None:
    first = _dimension(terms[0], units)
    for term in terms[1:]:
        other = _dimension(term, units)
        if other.dimensionality != first.dimensionality:
            raise ExpressionError(
                f"mixes dimensions in {where}: '{terms[0]}' is {first.dimensionality} "
                f"but '{term}' is {other.dimensionality}")


def check_equation(lhs: sympy.Expr, rhs: sympy.Expr,
                   units: dict[sympy.Symbol, pint.Quantity]) -> None:
    """Every additive term of both sides has one dimension; raises ExpressionError naming two
    terms that differ."""
    terms = [*sympy.Add.make_args(sympy.expand(lhs)), *sympy.Add.make_args(sympy.expand(rhs))]
    terms = [t for t in terms if t != 0]
    if len(terms) > 1:
        _same_dimension(terms, units, "its terms")
    elif terms:
        _dimension(terms[0], units)
