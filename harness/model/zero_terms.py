"""Unknowns whose term is identically zero, which sympy's automatic simplification does
not see (``K*(sin(x)^2 + cos(x)^2 - 1)``): such an unknown cancels out, and a log could
never identify it.

Deciding that an expression is zero symbolically has no time bound; numerically it is:
the term is evaluated at random points in 60 and in 120 significant digits.  A term that
is not zero has the same value in both; one that is zero leaves only its rounding, which
falls by about 60 orders of magnitude from the one precision to the other.
"""
from __future__ import annotations

from collections.abc import Iterable, Sequence

import mpmath
import numpy as np
import sympy

#: Random points at which a term is evaluated; a term is zero when it is at all of them
#: (that it is at least a few).
POINTS = 12
LEAST_POINTS = 3
#: Significant digits of the two evaluations, and the fall of a zero's value between them.
DIGITS = (60, 120)
ZERO_FALL = 1e-40
SAME = 1e-30


def _value(function: object, point: Sequence[mpmath.mpf], digits: int) -> complex | None:
    """The term at ``point`` in ``digits`` digits, or None where it has no finite real
    value (sqrt of a negative number, a pole)."""
    with mpmath.workdps(digits):
        try:
            value = function(*(mpmath.mpf(v) for v in point))  # type: ignore[operator]
        except (ValueError, ZeroDivisionError, OverflowError, TypeError):
            return None
        if isinstance(value, mpmath.mpc):
            if value.imag != 0:
                return None
            value = value.real
        try:
            value = mpmath.mpf(value)
        except (TypeError, ValueError):
            return None
        return value if mpmath.isfinite(value) else None


def identically_zero(term: sympy.Expr, symbols: Sequence[sympy.Symbol],
                     seed: int = 0) -> bool:
    """``term`` (a function of ``symbols``, numbers and constants only) is zero wherever
    it has a value: True only when it is zero at several random points and no point shows
    a value."""
    if term == 0:
        return True
    free = sorted(term.free_symbols, key=str)
    if not set(free) <= set(symbols):
        return False  # a name left symbolic: not decided here
    function = sympy.lambdify(free, term, modules="mpmath", dummify=True)
    rng = np.random.default_rng(seed)
    zeros = 0
    for k in range(POINTS):
        # magnitudes from 1e-3 to 10 (a term zero on a band, abs(x - 3) - (x - 3), is
        # not taken for zero; larger ones, exp(x)^2 beyond 1e60, would cancel beyond the
        # digits); half the points positive (sqrt, log have values there),
        # half of either sign
        point = 10.0 ** rng.uniform(-3.0, 1.0, len(free)) * (
            1 if k % 2 == 0 else rng.choice([-1, 1], len(free)))
        low, high = (_value(function, [float(v) for v in point], d) for d in DIGITS)
        if low is None or high is None:
            continue
        if high == 0 or abs(high) <= ZERO_FALL * abs(low):
            zeros += 1
        elif abs(high - low) <= SAME * abs(high):
            return False
    return zeros >= LEAST_POINTS


def cancelled(terms: Iterable[tuple[str, Sequence[sympy.Expr]]],
              symbols: Sequence[sympy.Symbol]) -> list[str]:
    """The names of the unknowns whose terms, one per equation, are all identically zero."""
    return [name for name, per_equation in terms
            if all(identically_zero(t, symbols) for t in per_equation)]
