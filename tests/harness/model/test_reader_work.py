"""Model files built to make the reader work without bound: huge numbers and powers,
long sums, deep nesting, look-alike letters, hostile unit strings, deeply nested TOML
and files that never end.  Each is refused within seconds with exit status 2 and a
message naming the problem, never a traceback, a hang or gigabytes of memory; names
that look like functions or constants mean what the file declares.
"""
from __future__ import annotations

import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from cli_runner import FMU_DIR, REPO, cli, refused, shell

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


MODEL = '''[model]
coordinates = ["{c}"]
inputs = ["F"]
equations = ["{eq}"]

[parameters]
M = {{ nominal = 1, unit = "kg" }}
Fv = {{ nominal = 1, unit = "kg/s" }}
{extra}'''
UNITS = '[units]\n{c} = "{unit}"\nF = "N"\n'
SECONDS = 10.0  # generous for a loaded machine; the old code took minutes or forever


def model(path: Path, eq: str = "M*der(x,2) + Fv*der(x) = F", c: str = "x",
          extra: str = "") -> Path:
    path.write_text(MODEL.format(c=c, eq=eq, extra=extra), encoding="utf-8")
    return path


def fmu_refuses(tmp_path: Path, path: Path, *words: str) -> str:
    """`fmu --model` (the reader, then nothing else) refuses it in time, naming it."""
    start = time.monotonic()
    code, text = cli(["fmu", "--model", str(path), "--out", str(tmp_path / "out")])
    assert time.monotonic() - start < SECONDS, text
    assert code == 2, text
    refused(code, text, str(path), *words)
    return text


@pytest.mark.parametrize("eq, words", [
    ("M*der(x,2) + Fv*der(x)*9^9^9^9 = F", ["beyond the range of float64"]),
    ("M*der(x,2) + Fv*der(x)*2^2^2^2^2 = F", ["beyond the range of float64"]),
    ("M*der(x,2) + Fv*der(x)*10^400 = F", ["10**400", "beyond the range of float64"]),
    ("M*der(x,2) + Fv*der(x)*exp(1000) = F", ["exp(1000)"]),
    ("M*der(x,2) + Fv*der(x) + (M+Fv)^100000 = F", ["power 100000"]),
    ("M*der(x,2) + Fv*der(x) + ((x^60)^60)^60 = F", ["power 216000"]),
    ("M*der(x,2) + Fv*(-8)^(1/3)*der(x) = F", ["(-8)**(1/3)", "no real value"]),
    ("M*der(x,2) + Fv*der(x)*sqrt(-1) = F", ["sqrt(-1)", "no real value"]),
    ("M*der(x,2) + Fv*der(x)/0 = F", ["divides by zero"]),
    ("M*der(x,2) + Fv*der(x) + " + "*".join(f"(x+F+{k}*der(x))" for k in range(1, 30))
     + " = F", ["terms once multiplied out"]),
    ("M*der(x,2) + Fv*der(x)" + " + x" * 100000 + " = F", ["characters long"]),
    ("M*der(x,2) + Fv*der(x)" + " + x" * 1500 + " = F", ["nested more than"]),
    ("M*der(x,2) + Fv*der(x)" + "*x" * 6000 + " = F", ["nested more than"]),
    ("M*der(x,2) + Fv*der(x) + " + "-" * 10000 + "x = F", ["nested more than"]),
    ("M*der(x,2) + Fv*der(x) + " + "sin(" * 150 + "x" + ")" * 150 + " = F", ["nests"]),
    ("M*der(x,2) + Fv*der(x)*" + "9" * 5000 + " = F", ["equation 1"]),
    ("M*der(\uff58,2) + Fv*der(x) = F", ["U+FF58", "ASCII"]),  # fullwidth x
    ("M*der(\u0445,2) + Fv*der(x) = F", ["U+0445", "ASCII"]),  # Cyrillic x
])
def test_expressions_beyond_the_bounds_are_refused_in_time(tmp_path, eq, words):
    fmu_refuses(tmp_path, model(tmp_path / "m.toml", eq), "equation 1", *words)


def test_a_term_too_tangled_to_simplify_is_refused_in_time(tmp_path):
    eq = "M*der(x,2) + M*(" + "+".join(f"Fv*sin({k}*x)" for k in range(1, 150)) + ") = F"
    fmu_refuses(tmp_path, model(tmp_path / "m.toml", eq), "not linear", "Fv")


def test_a_long_legal_sum_is_read_in_time(tmp_path):
    eq = "M*der(x,2) + Fv*der(x) + " + "+".join(f"Fv*sin({k}*x)" for k in range(1, 300)) \
        + " = F"
    from harness.model import read_model
    start = time.monotonic()
    read_model(model(tmp_path / "m.toml", eq))
    assert time.monotonic() - start < SECONDS


@pytest.mark.parametrize("unit, words", [
    ("9**9**9*kg", ["power to a power"]),
    ("kg*9**12", ["number 9"]),
    ("1e400*kg", ["1e400"]),
    ("kg**(1,)", ["','"]),
    ("m**100", ["power 100"]),
    ("degC", ["offset"]),
    ("degF", ["offset"]),
    ("m*" * 50_000 + "m", ["characters"]),
])
def test_hostile_unit_strings_are_refused_in_time(tmp_path, unit, words):
    path = model(tmp_path / "m.toml", extra=UNITS.format(c="x", unit=unit))
    fmu_refuses(tmp_path, path, "unit of x", *words)


@pytest.mark.parametrize("unit, exponent", [
    ("kg**1e400/V", "1e400"),        # pint got kg**inf and worked its base units out forever
    ("kg**1e400", "1e400"),          # was accepted as [mass]**inf
    ("kg**1e3", "1e3"),              # was "(34, 'Numerical result out of range')"
    ("kg^999999999", "999999999"),   # was "power 999": only the first three digits read
    ("kg**(1/1e400)", "(1/1e400)"),
    ("kg**1_000", "1_000"),
])
def test_a_unit_exponent_is_read_whole_and_bounded(tmp_path, unit, exponent):
    """A parameter's unit: the exponent is its whole number token, refused unless a plain
    number of at most 12, in time and naming the unit and the exponent (a separate
    process: the old reader never returned from kg**1e400/V)."""
    path = tmp_path / "m.toml"
    path.write_text(MODEL.format(c="x", eq="M*der(x,2) + Fv*der(x) = F", extra="")
                    .replace('unit = "kg/s"', f'unit = "{unit}"'), encoding="utf-8")
    result = shell(["fmu", "--model", str(path), "--out", str(tmp_path / "out")], timeout=60)
    refused(result.returncode, result.stderr, "parameter Fv", f"'{unit}'")
    assert result.returncode == 2, result.stderr
    assert (f"the exponent {exponent} is not a plain number" in result.stderr
            or f"raises to the power {exponent} (" in result.stderr), result.stderr
    assert "(34," not in result.stderr and not (tmp_path / "out").exists()


def test_a_huge_unit_string_in_a_huge_file_is_refused_by_its_size(tmp_path):
    path = model(tmp_path / "m.toml", extra=UNITS.format(c="x", unit="m" * (100 << 20)))
    fmu_refuses(tmp_path, path, "larger than")


@pytest.mark.parametrize("extra, words", [
    ("[constants]\nk = " + "[" * 100_000 + "]" * 100_000, ["nested more than"]),
    ("[constants]\nk = " + "{a=" * 5000 + "1" + "}" * 5000, ["nested more than"]),
    ("[constants]\n" + ".".join(["a"] * 100_000) + " = 1", ["dotted key"]),
    ("[constants]\n" + '"a".' * 100_000 + "a = 1", ["dotted key"]),
    ("[constants]\n" + "".join(f"k{i} = 1\n" for i in range(100_000)), ["larger than"]),
    ("[constants]\n" + "".join(f"k{i} = 1\n" for i in range(5000)), ["at most 1024"]),
])
def test_deep_or_huge_toml_is_refused_in_time(tmp_path, extra, words):
    fmu_refuses(tmp_path, model(tmp_path / "m.toml", extra=extra), *words)


def _limited() -> None:
    """The child's address space: a reader that trusts st_size fails, not the machine."""
    resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))


def test_a_model_path_to_a_device_is_read_with_a_cap(tmp_path):
    """A link to /dev/zero (st_size 0, no end): refused after at most the cap."""
    link = tmp_path / "zero.toml"
    link.symlink_to(os.devnull.replace("null", "zero"))  # read only, never written
    result = subprocess.run([sys.executable, "-m", "harness", "--fmu-dir", str(FMU_DIR),
                             "fmu", "--model", str(link), "--out", str(tmp_path / "out")],
                            cwd=REPO, capture_output=True, text=True, timeout=60,
                            preexec_fn=_limited)
    assert result.returncode == 2, result.stderr[-2000:]
    refused(result.returncode, result.stderr, str(link), "larger than", "not a regular file")


def test_a_model_path_to_a_pipe_is_refused_without_waiting(tmp_path):
    """A named pipe: opening it would wait for a writer that never comes."""
    pipe = tmp_path / "model.toml"
    os.mkfifo(pipe)
    result = subprocess.run([sys.executable, "-m", "harness", "--fmu-dir", str(FMU_DIR),
                             "fmu", "--model", str(pipe), "--out", str(tmp_path / "out")],
                            cwd=REPO, capture_output=True, text=True, timeout=60)
    assert result.returncode == 2, result.stderr[-2000:]
    refused(result.returncode, result.stderr, str(pipe), "a pipe or a socket")


@pytest.mark.parametrize("name", ["e", "arctan", "E", "I", "numpy", "x0"])
def test_a_coordinate_named_like_a_constant_or_function_means_the_coordinate(tmp_path,
                                                                              name):
    """exp(1) stays e and atan stays the function, whatever the coordinate is called:
    the same model with the coordinate named y gives the same numbers."""
    from harness.model import read_model

    eq = "M*der({c},2) + Fv*exp(1)*der({c}) + atan({c}) = F"
    ours = read_model(model(tmp_path / "a.toml", eq.format(c=name), c=name))
    plain = read_model(model(tmp_path / "b.toml", eq.format(c="y"), c="y"))
    rng = np.random.default_rng(1)
    q, qd, qdd, u = (rng.normal(size=(50, 1)) for _ in range(4))
    for a, b in zip(ours.regressor(q, qd, qdd, u), plain.regressor(q, qd, qdd, u)):
        assert np.array_equal(a, b)


def test_the_cli_answers_a_power_tower_at_once(tmp_path):
    """As a user runs it: a separate process, answered long before its timeout."""
    path = model(tmp_path / "m.toml", "M*der(x,2) + Fv*der(x)*9^9^9^9 = F")
    result = shell(["fmu", "--model", str(path), "--out", str(tmp_path / "out")],
                   timeout=60)
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert "float64" in result.stderr
