"""Units with pint, for everything the harness reads: one registry for the process,
unit strings as quantities, and the factor that brings a logged column's unit to the
unit the computation works in (s, rad, m, N.m/A ...), its dimension checked."""
from __future__ import annotations

import math
import re
from functools import lru_cache
from typing import TYPE_CHECKING

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
# A power operator and its exponent: a small number, maybe in parentheses or a fraction.
_POWER = re.compile(r"(\*\*|\^)\s*")
_EXPONENT = re.compile(r"\(?\s*[-+]?\s*(\d{1,3}(?:\.\d{1,6})?)\s*(?:/\s*\d{1,3}\s*)?\)?")
_EXPONENT_AFTER_POWER = re.compile(_POWER.pattern + _EXPONENT.pattern)
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
    for power in _POWER.finditer(unit):
        exponent = _EXPONENT.match(unit, power.end())
        if exponent is None or not exponent.group(0).strip():
            raise ValueError(f"'{unit}': a power in a unit must be a number (m^2, s^-1)")
        if float(exponent.group(1)) > MAX_UNIT_EXPONENT:
            raise ValueError(f"'{unit}' raises to the power {exponent.group(0).strip()} (at "
                             f"most {MAX_UNIT_EXPONENT} in size)")
        if _POWER.match(unit, exponent.end()):
            raise ValueError(f"'{unit}' raises a power to a power; write one exponent")
    bases = _POWER.sub(" ", _EXPONENT_AFTER_POWER.sub(" ", unit))
    for number in _NUMBER.finditer(bases):  # pint would evaluate it exactly: 9*9*9...
        if number.group(0) != "1":
            raise ValueError(f"'{unit}' has the number {number.group(0)} outside an exponent; "
                             f"a unit is names and powers (write the factor as a prefix: "
                             f"kN, mm)")


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
    if not value._is_multiplicative:  # degC: products and factors are meaningless
        raise ValueError(f"'{unit}' is a unit with an offset (a temperature scale's zero); "
                         f"write kelvin (K) or a difference (delta_degC)")
    try:
        magnitude = float(value.to_base_units().magnitude)
    except (OverflowError, ValueError, ZeroDivisionError, TypeError) as exc:
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
