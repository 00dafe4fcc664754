"""Units with pint, for everything the harness reads: one registry for the process,
unit strings as quantities, and the factor that brings a logged column's unit to the
unit the computation works in (s, rad, m, N.m/A ...), its dimension checked."""
from __future__ import annotations

import math
import numbers
import re
from collections.abc import Iterable
from functools import lru_cache
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pint loads in a quarter of a second: on first use, not with the CLI
    import pint

# '.' as a product between unit names ("N.s/m", "kg.m^2"), never inside a number ("1.5").
_DOT_PRODUCT = re.compile(r"(?<=[A-Za-z0-9_)\]])\.(?=[A-Za-z_(])")

# pint evaluates a unit string's numbers as exact Python numbers ("9**9**9*kg" is a
# number of 370 million digits), so a unit string is bounded before pint sees it:
#: Characters in a unit string ("kg.m^2/s^2" is 10; a compound unit is a few dozen).
MAX_UNIT_CHARS = 100
#: |exponent| of a power in a unit (m^3, s^-2; no unit is raised beyond a few).
MAX_UNIT_EXPONENT = 12
# What a unit string may hold: names (any letters, as pint knows "µm"), numbers, spaces
# and the operators of a product, quotient and power; no ',' (a tuple) or anything else.
_UNIT_CHARACTERS = re.compile(r"[\w .*/^()+\-%]*")
# A power operator, then its exponent read whole: a sign and a number token, maybe in
# parentheses as a fraction ("^2", "**-1", "^(1/2)").  A number token is every digit,
# letter, '_' and decimal point that follow its first digit ("1e400", "999999999",
# "1_000", "2.5.1" are one token each: never its first digits alone), but not a '.'
# before a name ("m^2.s" is m^2 times s); the token must then be a plain number.
_POWER = re.compile(r"(\*\*|\^)\s*")
_TOKEN = r"\d\w*(?:\.\d\w*)*"
_EXPONENT = re.compile(rf"\(\s*(?P<inner>[-+]?\s*{_TOKEN})\s*(?:/\s*(?P<below>{_TOKEN})\s*)?\)"
                       rf"|(?P<bare>[-+]?\s*{_TOKEN})")
# A plain number: digits, maybe a decimal part (no exponent, no '_', no leading zeros).
_PLAIN = re.compile(r"[-+]?(?:0|[1-9]\d*)(?:\.\d+)?")
# A number that is not part of a name (m2, H2O): outside exponents only "1" ("1/s").
_NUMBER = re.compile(r"(?<![\w.])\d[\w.]*")

#: The units a log's time column may be in (the --time-unit choices).
TIME_UNITS = ("s", "ms", "us", "ns", "min")
#: The units a revolute joint's position column may be in (--angle-unit).
ANGLE_UNITS = ("rad", "deg")
#: The units a prismatic joint's position column may be in (--length-unit).
LENGTH_UNITS = ("m", "mm")


@lru_cache(maxsize=1)
def registry() -> pint.UnitRegistry:
    """One registry for the process (building one takes a while)."""
    import pint
    return pint.UnitRegistry()


def _check_exponent(unit: str, exponent: re.Match[str]) -> None:
    """ValueError unless the exponent (numerator, maybe denominator) is plain numbers and
    at most MAX_UNIT_EXPONENT in size; the message names the unit and the exponent."""
    numerator = "".join((exponent["inner"] or exponent["bare"]).split())
    written = exponent.group(0).strip()
    for number in (numerator, exponent["below"]):
        if number is not None and not _PLAIN.fullmatch(number):
            raise ValueError(f"'{unit}': the exponent {written} is not a plain number (a power "
                             f"in a unit is written as m^2, s^-1, m^0.5 or m^(1/2), at most "
                             f"{MAX_UNIT_EXPONENT} in size)")
    below = 1.0 if exponent["below"] is None else float(exponent["below"])
    if below == 0.0:
        raise ValueError(f"'{unit}': the exponent {written} divides by 0")
    if abs(float(numerator) / below) > MAX_UNIT_EXPONENT:
        raise ValueError(f"'{unit}' raises to the power {written} (at most "
                         f"{MAX_UNIT_EXPONENT} in size)")


def _check_unit_text(unit: str) -> None:
    """ValueError unless ``unit`` is short, of unit characters, and its powers are small
    numbers applied once (never a power of a power)."""
    if len(unit) > MAX_UNIT_CHARS:
        raise ValueError(f"a unit of {len(unit)} characters ('{unit[:20]}...'): a unit is at "
                         f"most {MAX_UNIT_CHARS}")
    if not _UNIT_CHARACTERS.fullmatch(unit):
        bad = next(c for c in unit if not _UNIT_CHARACTERS.fullmatch(c))
        raise ValueError(f"'{unit}' has the character {bad!r}, which no unit has (names, "
                         f"numbers, spaces and * / ^ ( ) only)")
    bases = unit
    for power in _POWER.finditer(unit):
        exponent = _EXPONENT.match(unit, power.end())
        if exponent is None:
            raise ValueError(f"'{unit}': a power in a unit must be a number (m^2, s^-1)")
        _check_exponent(unit, exponent)
        if _POWER.match(unit, exponent.end()):
            raise ValueError(f"'{unit}' raises a power to a power; write one exponent")
        blank = " " * (exponent.end() - power.start())  # the bases are checked below
        bases = bases[:power.start()] + blank + bases[exponent.end():]
    for number in _NUMBER.finditer(bases):  # pint would evaluate it exactly: 9*9*9...
        if number.group(0) != "1":
            raise ValueError(f"'{unit}' has the number {number.group(0)} outside an exponent; "
                             f"a unit is names and powers (write the factor as a prefix: "
                             f"kN, mm)")


def _check_powers(unit: str, powers: Iterable[tuple[str, Any]], what: str) -> None:
    """ValueError for a power that is not a finite real number (pint works an inf-th
    power of a unit out without end): a second guard behind the exponents' check on the
    text."""
    for name, power in powers:
        if not (isinstance(power, numbers.Real) and math.isfinite(power)):
            raise ValueError(f"'{unit}' gives the {what} {name} the power {power}; a power "
                             f"in a unit is a plain number of at most {MAX_UNIT_EXPONENT} "
                             f"in size")


def quantity(unit: str) -> pint.Quantity:
    """One of ``unit``: "kg", "N.s/m", "kN", "deg", "" (dimensionless). Raises ValueError,
    also for a unit with an offset (degC, degF: a scale's zero is not a factor) and for
    a string beyond the bounds above (checked before pint evaluates it)."""
    _check_unit_text(unit)
    text = _DOT_PRODUCT.sub("*", unit.strip())
    if not text:
        return registry().Quantity(1.0)
    try:
        value = registry().Quantity(1.0, text)
    except Exception as exc:  # pint raises several unrelated types for a bad string
        raise ValueError(f"'{unit}' is not a unit pint knows ({type(exc).__name__}: {exc})") \
            from None
    _check_powers(unit, value.unit_items(), "unit")  # pint's own reading: never m**inf
    if not value._is_multiplicative:  # degC: products and factors are meaningless
        raise ValueError(f"'{unit}' is a unit with an offset (a temperature scale's zero); "
                         f"write kelvin (K) or a difference (delta_degC)")
    _check_powers(unit, value.dimensionality.items(), "dimension")
    try:
        magnitude = float(value.to_base_units().magnitude)
    except OverflowError:  # Qm^12: 1e360 m^12; the message of errno 34 says nothing
        raise ValueError(f"'{unit}' in SI base units is beyond the range of float64 "
                         f"(about 1.8e308)") from None
    except (ValueError, ZeroDivisionError, TypeError) as exc:
        raise ValueError(f"'{unit}' is not a usable unit ({exc})") from None
    if not (math.isfinite(magnitude) and magnitude > 0.0):
        raise ValueError(f"'{unit}' is not a positive finite multiple of SI units "
                         f"({magnitude:g})")
    return value


def si_factor(unit: str) -> float:
    """What one ``unit`` is in SI base units (1000 for "kN", pi/180 for "deg")."""
    return float(quantity(unit).to_base_units().magnitude)


def factor(unit: str, target: str) -> float:
    """What one ``unit`` is in ``target`` (1e-3 for "ms" to "s", pi/180 for "deg" to
    "rad"); ValueError when the two are not of one dimension (a time column in "deg")."""
    import pint

    source, goal = quantity(unit), quantity(target)
    try:
        value = float(source.to(goal.units).magnitude) / float(goal.magnitude)
    except pint.DimensionalityError:
        raise ValueError(f"'{unit}' is not a unit of {goal.dimensionality} like "
                         f"'{target}'") from None
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"'{unit}' is not a positive multiple of '{target}'")
    return value
