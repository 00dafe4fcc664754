"""Split an equation into its regressor: sum_k theta_k phi_k = known part."""
from __future__ import annotations

from dataclasses import dataclass

import sympy

from .expressions import ExpressionError

#: Operations of an expression that sympy.simplify is asked to tidy: its time grows far
#: faster than the expression (minutes for a few hundred operations), and a coefficient
#: it has to tidy is one where parameters cancel, which a short expression shows.
MAX_SIMPLIFY_OPS = 200


def _simplified(expr: sympy.Expr) -> sympy.Expr:
    """``sympy.simplify(expr)`` when ``expr`` is small enough to be worth it, else as it is
    (then a parameter that would cancel still shows, and the equation is refused)."""
    return sympy.simplify(expr) if sympy.count_ops(expr) <= MAX_SIMPLIFY_OPS else expr


def _short(expr: sympy.Expr, limit: int = 200) -> str:
    text = str(expr)
    return text if len(text) <= limit else text[:limit - 3] + "..."


@dataclass(frozen=True)
class Split:
    """``lhs - rhs = sum_k parameters[k] * terms[k] - known``, so ``Y theta = r`` with r = known."""

    terms: tuple[sympy.Expr, ...]
    known: sympy.Expr


def split_linear(residual: sympy.Expr, parameters: list[sympy.Symbol]) -> Split:
    """Regressor terms and known part of ``residual`` (= lhs - rhs), which must be affine in
    the parameters: each derivative by a parameter must be free of every parameter (this
    catches products, powers, quotients and functions of parameters alike)."""
    unknown = set(parameters)
    terms = []
    for theta in parameters:
        phi = sympy.diff(residual, theta)
        if phi.free_symbols & unknown:  # simplify only when needed: it is slow on large models
            phi = _simplified(phi)
        tangled = sorted(str(s) for s in phi.free_symbols & unknown)
        if tangled or phi.has(sympy.DiracDelta):
            with_ = ", ".join(tangled) if tangled else str(theta)
            raise ExpressionError(f"is not linear in the unknown parameter {theta}: the "
                                  f"coefficient of {theta} is '{_short(phi)}', which depends "
                                  f"on {with_}")
        terms.append(phi)
    known = -residual.subs({theta: 0 for theta in parameters})
    rest = sympy.expand(residual - sum((t * p for t, p in zip(terms, parameters)),
                                       sympy.Integer(0)) + known)
    # A guard: the derivative test above should leave nothing here.
    if rest != 0 and _simplified(rest) != 0:
        raise ExpressionError(f"is not linear in the unknown parameters (remainder "
                              f"'{_short(rest)}')")
    return Split(tuple(terms), known)


def check_accelerations(residual: sympy.Expr, accelerations: list[sympy.Symbol]) -> None:
    """The equation must be affine in the accelerations (form M(q) q'' + h(q, q', u) = 0),
    so the observer can solve it for them."""
    for acc in accelerations:
        coefficient = sympy.diff(residual, acc)
        tangled = sorted(str(s) for s in coefficient.free_symbols if s in set(accelerations))
        if tangled or coefficient.has(sympy.DiracDelta):
            raise ExpressionError(f"is not linear in the accelerations: the coefficient of "
                                  f"{acc} is '{_short(coefficient)}'")
