"""A bad model file raises ModelFileError naming the file and the problem, never a model."""
from __future__ import annotations

from pathlib import Path

import pytest

from harness.model import ModelFileError, read_model

GOOD = """
[model]
coordinates = ["x"]
inputs = ["F"]
equations = ["M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = F"]
[parameters]
M  = { nominal = 100, unit = "kg" }
Fv = { nominal = 0, unit = "N.s/m" }
Fc = { nominal = 0, unit = "N" }
OF = { nominal = 0, unit = "N" }
[constants]
[units]
x = "m"
F = "N"
[columns]
t = "t"
x = "qm"
F = "force"
"""
EQUATION = "M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = F"


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "machine.toml"
    path.write_text(text)
    return path


def _error(tmp_path: Path, text: str) -> str:
    path = _write(tmp_path, text)
    with pytest.raises(ModelFileError) as caught:
        read_model(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: "), message
    return message


def _with_equation(equation: str) -> str:
    return GOOD.replace(EQUATION, equation)


def test_the_good_file_reads(tmp_path):
    model = read_model(_write(tmp_path, GOOD))
    assert model.parameter_names == ("M", "Fv", "Fc", "OF")


@pytest.mark.parametrize("equation, culprit", [
    ("M*der(x,2) + Fv^2*der(x) + Fc*sign(der(x)) + OF = F", "Fv"),
    ("M*der(x,2) + Fv**2*der(x) + Fc*sign(der(x)) + OF = F", "Fv"),
    ("Fv*M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = F", "M"),
    ("M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF + sin(M) = F", "M"),
    ("M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = F/M", "M"),
    ("M*der(x,2) + Fv*der(x) + Fc*sign(der(x)*Fc) + OF = F", "Fc"),
    ("M*der(x,2) + Fv*der(x) + abs(Fc)*sign(der(x)) + OF = F", "Fc"),
])
def test_nonlinear_in_an_unknown(tmp_path, equation, culprit):
    message = _error(tmp_path, _with_equation(equation))
    assert "equation 1" in message and "not linear in the unknown parameter" in message
    assert culprit in message


def test_nonlinear_in_the_acceleration(tmp_path):
    message = _error(tmp_path, _with_equation(
        "M*der(x,2) + Fv*der(x) + Fc*sign(der(x,2)) + OF = F"))
    assert "not linear in the accelerations" in message


def test_a_coordinate_without_its_second_derivative(tmp_path):
    message = _error(tmp_path, _with_equation("M*der(x) + Fv*x + Fc*sign(der(x)) + OF = F"))
    assert "has no der(x,2)" in message


def test_each_equation_needs_its_own_coordinates_second_derivative(tmp_path):
    text = GOOD.replace('coordinates = ["x"]', 'coordinates = ["x", "y"]').replace(
        f'equations = ["{EQUATION}"]',
        'equations = ["M*der(x,2) + Fv*der(x) + OF = F", "Fc*der(x,2) + Fc*y = 0"]')
    text = text.replace('x = "m"', 'x = "m"\ny = "m"')
    assert "equation 2" in (message := _error(tmp_path, text)) and "der(y,2)" in message


@pytest.mark.parametrize("section, line", [
    ("[constants]", "M = 2.0"),            # parameter and constant
    ("[constants]", "x = 2.0"),            # coordinate and constant
    ("[parameters]", 'F = { nominal = 1, unit = "N" }'),   # input and parameter
])
def test_a_name_used_twice(tmp_path, section, line):
    message = _error(tmp_path, GOOD.replace(section, f"{section}\n{line}"))
    assert "is used twice" in message


def test_a_name_used_twice_within_coordinates_and_inputs(tmp_path):
    message = _error(tmp_path, GOOD.replace('inputs = ["F"]', 'inputs = ["F", "x"]'))
    assert "'x' is used twice: as coordinate and as input" in message


@pytest.mark.parametrize("equation, what", [
    ("M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF + Kx*x = F", "unknown name 'Kx'"),
    ("M*der(x,2) + Fv*der(x) + Fc*sgn(der(x)) + OF = F", "unknown function 'sgn'"),
    ("M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = F + __import__('os').getpid()",
     "not a plain function name"),
    ("M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = F + __import__('os')",
     "unknown function '__import__'"),
    ("M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = F.real", "Attribute"),
    ("M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = (lambda: F)()", "not a plain function"),
    ("M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = [F][0]", "Subscript"),
    ("M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = 'F'", "not a real number"),
    ("M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = sin", "without calling it"),
    ("M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = sin(F, 2)", "2 arguments"),
    ("M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = sin(*[F])", "Starred"),
    ("M*der(x,3) + Fv*der(x) + Fc*sign(der(x)) + OF = F", "order other than 1 or 2"),
    ("M*der(x,2) + Fv*der(F) + Fc*sign(der(x)) + OF = F", "der() on something other"),
    ("M*der(x,2) + Fv*der(x+1) + Fc*sign(der(x)) + OF = F", "der() on something other"),
    ("M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF == F", "one '='"),
    ("M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF", "one '='"),
    ("M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = F = 0", "one '='"),
    ("M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = F +", "not an expression"),
])
def test_unknown_names_and_syntax_in_an_equation(tmp_path, equation, what):
    message = _error(tmp_path, _with_equation(equation))
    assert "equation 1" in message and what in message


def test_time_is_not_a_name_of_the_equations(tmp_path):
    message = _error(tmp_path, _with_equation(
        "M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = F*t"))
    assert "unknown name 't'" in message


@pytest.mark.parametrize("equations", [
    "[]",
    f'["{EQUATION}", "M*der(x,2) = F"]',
])
def test_the_count_of_equations_differs_from_the_coordinates(tmp_path, equations):
    message = _error(tmp_path, GOOD.replace(f'equations = ["{EQUATION}"]',
                                            f"equations = {equations}"))
    assert "equation(s) for 1 coordinate(s)" in message


def test_a_parameter_in_no_equation(tmp_path):
    text = GOOD.replace("[constants]", "[constants]").replace(
        'OF = { nominal = 0, unit = "N" }',
        'OF = { nominal = 0, unit = "N" }\nKs = { nominal = 1, unit = "N/m" }')
    assert "Ks appear in no equation" in _error(tmp_path, text)


def test_a_parameter_that_cancels_out_is_in_no_equation(tmp_path):
    message = _error(tmp_path, _with_equation(
        "M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF - OF = F"))
    assert "OF appear in no equation" in message


@pytest.mark.parametrize("text", [
    GOOD.replace('M  = { nominal = 100, unit = "kg" }', 'M  = { nominal = 100, unit = "kg" '),
    GOOD.replace("[units]", "[model]"),       # a table defined twice
    "this is not toml",
])
def test_invalid_toml(tmp_path, text):
    assert "is not valid TOML" in _error(tmp_path, text)


@pytest.mark.parametrize("section", ["model", "parameters"])
def test_a_missing_section(tmp_path, section):
    start = GOOD.index(f"[{section}]")
    end = GOOD.index("\n[", start + 1)
    assert f"has no [{section}] section" in _error(tmp_path, GOOD[:start] + GOOD[end + 1:])


def test_a_misspelt_section_or_key(tmp_path):
    assert "unknown section [parameter]" in _error(
        tmp_path, GOOD.replace("[parameters]", "[parameter]"))
    assert "unknown keys ['equation']" in _error(
        tmp_path, GOOD.replace("equations =", "equation ="))
    assert "no 'coordinates' list" in _error(
        tmp_path, GOOD.replace('coordinates = ["x"]', ""))


def test_more_than_seven_coordinates(tmp_path):
    names = [f"q{i}" for i in range(1, 9)]
    text = f"""
[model]
coordinates = {names}
equations = {[f"m*der({q},2) = 0" for q in names]}
[parameters]
m = {{ nominal = 1 }}
"""
    assert "declares 8 coordinates; a model has 1 to 7" in _error(tmp_path, text)


def test_seven_coordinates_are_fine(tmp_path):
    names = [f"q{i}" for i in range(1, 8)]
    text = f"""
[model]
coordinates = {names}
equations = {[f"m*der({q},2) = 0" for q in names]}
[parameters]
m = {{ nominal = 1 }}
"""
    assert len(read_model(_write(tmp_path, text)).equations) == 7


@pytest.mark.parametrize("value", ["nan", "inf", "-inf", '"100"', "true"])
def test_a_nominal_value_that_is_not_a_finite_number(tmp_path, value):
    message = _error(tmp_path, GOOD.replace("nominal = 100", f"nominal = {value}"))
    assert "the nominal value of parameter M must be" in message


BIG = "1" + "0" * 400  # a TOML integer has any size; a float64 ends at 1.8e308


@pytest.mark.parametrize("old, new, said", [
    ("nominal = 100", f"nominal = {BIG}", "the nominal value of parameter M is an integer"),
    ("[constants]", f"[constants]\ng = {BIG}", "constant g is an integer"),
    ("[units]", f"[log]\nsample_rate = {BIG}\n[units]", "sample_rate is an integer"),
    ("M  = { nominal = 100,", f"M  = {{ range = [0, {BIG}], nominal = 100,",
     "parameter M: the upper end of its range is an integer"),
])
def test_an_integer_beyond_a_float_is_named(tmp_path, old, new, said):
    message = _error(tmp_path, GOOD.replace(old, new))
    assert said in message and "beyond a float64's range" in message


@pytest.mark.parametrize("number", ["0x10", "1_0", "0o7", "0b1"])
def test_a_number_not_written_in_decimal_is_refused(tmp_path, number):
    """Python would read 0x10 as 16 and 1_0 as 10: equations write numbers in decimal."""
    message = _error(tmp_path, GOOD.replace("+ OF = F", f"+ {number}*OF = F"))
    assert f"has the number '{number}': numbers are written in decimal" in message


def test_a_constant_that_is_not_finite(tmp_path):
    message = _error(tmp_path, GOOD.replace("[constants]", "[constants]\ng = nan"))
    assert "constant g must be finite" in message


@pytest.mark.parametrize("line, name", [("v = \"vel\"", "v"), ("M = \"mass\"", "M")])
def test_a_column_mapping_for_an_unknown_name(tmp_path, line, name):
    message = _error(tmp_path, GOOD.replace('F = "force"', f'F = "force"\n{line}'))
    assert f"[columns] maps ['{name}']" in message


def test_reserved_and_malformed_names(tmp_path):
    assert "'sin' is reserved" in _error(
        tmp_path, GOOD.replace('inputs = ["F"]', 'inputs = ["F", "sin"]'))
    assert "parameter name 'time' is reserved" in _error(  # the FMU's independent variable
        tmp_path, GOOD.replace("+ OF = F", "+ time = F").replace("OF = {", "time = {"))
    assert "'2x' is not a name" in _error(
        tmp_path, GOOD.replace('inputs = ["F"]', 'inputs = ["F", "2x"]'))
    assert "'t' is reserved" in _error(
        tmp_path, GOOD.replace('inputs = ["F"]', 'inputs = ["F", "t"]'))


def test_a_file_that_does_not_exist(tmp_path):
    with pytest.raises(ModelFileError, match="cannot be read"):
        read_model(tmp_path / "absent.toml")
