"""Units: pint reads the file's unit strings, every term of an equation has one dimension,
and the regressor works in SI so a file's choice of units changes no physical value."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from harness.model import ModelFileError, parse_model, read_model
from harness.model.units import quantity, si_factor

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"
EMPS = (EXAMPLES / "emps" / "emps.toml").read_text()
EQUATION = "M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = gtau*vir"


@pytest.mark.parametrize("unit, dimension, factor", [
    ("kg", "[mass]", 1.0),
    ("N", "[mass] * [length] / [time] ** 2", 1.0),
    ("N.s/m", "[mass] / [time]", 1.0),
    ("N.m", "[mass] * [length] ** 2 / [time] ** 2", 1.0),
    ("kg.m^2", "[mass] * [length] ** 2", 1.0),
    ("rad", "dimensionless", 1.0),
    ("m", "[length]", 1.0),
    ("mm", "[length]", 1e-3),
    ("kN", "[mass] * [length] / [time] ** 2", 1e3),
    ("deg", "dimensionless", np.pi / 180),
    ("", "dimensionless", 1.0),
    ("1", "dimensionless", 1.0),
])
def test_unit_strings(unit, dimension, factor):
    assert str(quantity(unit).dimensionality) == dimension
    assert si_factor(unit) == pytest.approx(factor, rel=1e-12)


def test_a_dot_in_a_number_stays_a_decimal_point():
    assert str(quantity("m^1.5.s").dimensionality) == "[length] ** 1.5 * [time]"


def _emps_error(text: str) -> str:
    with pytest.raises(ModelFileError) as caught:
        parse_model(text, source="emps.toml")
    assert str(caught.value).startswith("emps.toml: ")
    return str(caught.value)


def test_terms_of_different_dimensions():
    message = _emps_error(EMPS.replace(EQUATION,
                                       "M*der(x,2) + Fv*x + Fc*sign(der(x)) + OF = gtau*vir"))
    assert "equation 1 ('M*der(x,2) + Fv*x" in message
    assert "is [mass] * [length] / [time] ** 2 but 'Fv*x' is [mass] * [length] / [time]" \
        in message


def test_a_parameter_with_the_wrong_unit():
    message = _emps_error(EMPS.replace('Fc = { nominal = 0, unit = "N" }',
                                       'Fc = { nominal = 0, unit = "kg" }'))
    assert "mixes dimensions" in message and "'Fc*sign(der(x))' is [mass]" in message


def test_a_constant_with_the_wrong_unit():
    message = _emps_error(EMPS.replace('unit = "N/V"', 'unit = "N/A"'))
    assert "'gtau*vir'" in message


def test_a_function_of_a_length():
    message = _emps_error(EMPS.replace("OF = gtau*vir", "OF*cos(x) = gtau*vir"))
    assert "takes cos of 'x', which has the dimension [length]" in message


def test_a_sum_inside_a_function_is_checked():
    message = _emps_error(EMPS.replace("sign(der(x))", "sign(der(x) + x)"))
    assert "mixes dimensions in a sum" in message


def test_a_unit_pint_does_not_know():
    message = _emps_error(EMPS.replace('x = "m"', 'x = "furlongz"'))
    assert "the unit of x:" in message and "not a unit pint knows" in message
    message = _emps_error(EMPS.replace('unit = "kg"', 'unit = "kgg"'))
    assert "the unit of parameter M:" in message


def test_units_for_every_coordinate_and_input():
    assert "gives no unit for vir" in _emps_error(EMPS.replace('vir = "V"\n', "", 1))
    assert "which are not coordinates or inputs" in _emps_error(
        EMPS.replace('vir = "V"', 'vir = "V"\nM = "kg"'))
    message = _emps_error(EMPS.replace('OF = { nominal = 0, unit = "N" }', "OF = { nominal = 0 }"))
    assert "OF have no unit" in message


def test_without_units_nothing_is_checked():
    text = EMPS.replace(EQUATION, "M*der(x,2) + Fv*x + Fc*sign(der(x)) + OF = gtau*vir")
    start = text.index("[units]")
    model = parse_model(text[:start] + text[text.index("[columns]"):])
    assert model.units == {}


def _physical(model, theta):
    """Each identified value in SI base units."""
    return np.array([value * si_factor(p.unit) for value, p in zip(theta, model.parameters)])


def test_changing_the_files_units_changes_no_physical_value():
    """The same motion written in mm, kN and kN.s/mm gives, by least squares, the same
    physical parameters (the regressor works in SI)."""
    metres = read_model(EXAMPLES / "emps" / "emps.toml")
    millimetres = parse_model(EMPS.replace('x = "m"', 'x = "mm"')
                              .replace('unit = "N.s/m"', 'unit = "kN.s/mm"')
                              .replace('Fc = { nominal = 0, unit = "N" }',
                                       'Fc = { nominal = 0, unit = "kN" }')
                              .replace('unit = "N/V"', 'unit = "kN/V"')
                              .replace("value = 35.15065188", "value = 0.03515065188"))
    t = np.linspace(0, 10, 5001)
    q = 0.1 * np.sin(t) + 0.02 * np.sin(7 * t)
    qd = 0.1 * np.cos(t) + 0.14 * np.cos(7 * t)
    qdd = -0.1 * np.sin(t) - 0.98 * np.sin(7 * t)
    truth = np.array([95.0, 203.0, 20.0, -3.0])
    force = truth @ np.stack([qdd, qd, np.sign(qd), np.ones_like(t)])
    vir = force / 35.15065188 + 1e-3 * np.random.default_rng(1).normal(size=t.size)
    found = {}
    for name, model, scale in (("m", metres, 1.0), ("mm", millimetres, 1e3)):
        Y, r = model.regressor(q * scale, qd * scale, qdd * scale, vir)
        theta, *_ = np.linalg.lstsq(Y[:, 0, :], r[:, 0], rcond=None)
        found[name] = _physical(model, theta)
    np.testing.assert_allclose(found["mm"], found["m"], rtol=1e-6)
    np.testing.assert_allclose(found["m"], truth, rtol=1e-3, atol=1e-2)


def test_an_angle_in_degrees_enters_the_functions_in_radians():
    text = (EXAMPLES / "pendulum" / "pendulum.toml").read_text()
    radians = parse_model(text)
    degrees = parse_model(text.replace('theta = "rad"', 'theta = "deg"'))
    angle, rate, acc, torque = np.random.default_rng(3).normal(size=(4, 100))
    deg = 180 / np.pi
    Y_rad, r_rad = radians.regressor(angle, rate, acc, torque)
    Y_deg, r_deg = degrees.regressor(angle * deg, rate * deg, acc * deg, torque)
    np.testing.assert_allclose(Y_deg, Y_rad, rtol=1e-12)
    np.testing.assert_allclose(r_deg, r_rad, rtol=1e-12)


def test_a_regularization_relative_to_the_column_scales_ignores_the_units():
    """Ridge toward the nominal values, weighted by each column's RMS: the same pull in
    m, N as in mm, kN (an absolute weight would pull differently in each)."""
    metres = read_model(EXAMPLES / "emps" / "emps.toml")
    kilo = parse_model(EMPS.replace('x = "m"', 'x = "mm"')
                       .replace('M  = { nominal = 100, unit = "kg" }',
                                'M  = { nominal = 0.1, unit = "kN.s^2/m" }')
                       .replace('unit = "N.s/m"', 'unit = "kN.s/mm"'))
    t = np.linspace(0, 10, 5001)
    q, qd, qdd = 0.1 * np.sin(t), 0.1 * np.cos(t), -0.1 * np.sin(t)
    vir = (95 * qdd + 203 * qd + 20 * np.sign(qd) - 3) / 35.15065188

    def ridge(model, scale, rho=0.1):
        Y, r = model.regressor(q * scale, qd * scale, qdd * scale, vir)
        Y, r = Y[:, 0, :], r[:, 0]
        weight = rho * len(r) * np.diag(model.column_scales(q * scale, qd * scale,
                                                            qdd * scale, vir) ** 2)
        theta = np.linalg.solve(Y.T @ Y + weight, Y.T @ r + weight @ model.nominal)
        return _physical(model, theta)
    np.testing.assert_allclose(ridge(kilo, 1e3), ridge(metres, 1.0), rtol=1e-9)
    assert abs(ridge(metres, 1.0)[1] / 203 - 1) > 0.01  # rho = 0.1 does pull
