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


def quantity(unit: str) -> pint.Quantity:
    """One of ``unit``: "kg", "N.s/m", "kN", "deg", "" (dimensionless). Raises ValueError."""
    text = _DOT_PRODUCT.sub("*", unit.strip())
    if not text:
        return registry().Quantity(1.0)
    try:
        value = registry().Quantity(1.0, text)
    except Exception as exc:  # pint raises several unrelated types for a bad string
        raise ValueError(f"'{unit}' is not a unit pint knows ({type(exc).__name__}: {exc})") \
            from None
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
