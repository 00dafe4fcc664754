"""harness.units: unit strings read by pint within bounds, as SI factors; a string that
is no unit, has an offset or reaches beyond float64 is named."""
from __future__ import annotations

import math

import pytest

from harness.units import factor, quantity, si_factor


@pytest.mark.parametrize("unit, expected", [("kg", 1.0), ("kN", 1e3), ("deg", math.pi / 180),
                                            ("N.s/m", 1.0), ("mm", 1e-3), ("", 1.0),
                                            ("rad/s^2", 1.0)])
def test_si_factors(unit, expected):
    assert si_factor(unit) == pytest.approx(expected, rel=1e-15)


def test_factors_between_units_of_one_dimension():
    assert factor("ms", "s") == pytest.approx(1e-3, rel=1e-15)
    assert factor("deg", "rad") == pytest.approx(math.pi / 180, rel=1e-15)
    with pytest.raises(ValueError, match="'deg' is not a unit of .*time"):
        factor("deg", "s")


@pytest.mark.parametrize("unit, said", [
    ("parsec_per_banana", "is not a unit pint knows"),
    ("degC", "a unit with an offset"),
    ("0*kg", "has the number 0 outside an exponent"),
    ("m^100", r"raises to the power 100 \(at most 12 in size\)"),
    ("kg" + "*kg" * 200, "characters"),
])
def test_a_unit_that_cannot_be_used_is_named(unit, said):
    with pytest.raises(ValueError, match=said):
        quantity(unit)


@pytest.mark.cli
def test_a_unit_never_has_a_power_that_is_not_finite():
    from harness.units import quantity
    for unit in ("kg**1e400", "kg**(1/1e400)", "m^(1/0)"):
        with pytest.raises(ValueError, match="exponent"):
            quantity(unit)
