"""The term program (harness/model/program.py): the core's C evaluates a model file's
regressor to the numbers of the Python model, on every example and on units that scale."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from harness.model import read_model
from harness.model.program import (
    MAX_STACK,
    NAME_SIZE,
    OPS,
    ProgramError,
    compile_program,
    evaluate_program,
)

REPO = Path(__file__).resolve().parents[3]
EXAMPLES = sorted((REPO / "examples").glob("*/*.toml"))


def test_the_ops_are_the_cores():
    header = (REPO / "fmu/src/core/term_program.h").read_text()
    enum = re.search(r"typedef enum \{(.*?)\} TpOp;", header, re.DOTALL).group(1)
    names = [name.strip() for name in enum.replace("\n", " ").split(",") if name.strip()]
    assert names[-1] == "TP_OP_COUNT"
    assert [name.removeprefix("TP_").lower() for name in names[:-1]] == [
        {"multiply": "multiply", "negate": "negate"}.get(op, op) for op in OPS]


def random_log(model, samples=500, seed=3):
    rng = np.random.default_rng(seed)
    n, m = len(model.coordinates), len(model.inputs)
    q = rng.uniform(-2, 2, (samples, n))
    qd = rng.uniform(-3, 3, (samples, n))
    qdd = rng.uniform(-30, 30, (samples, n))
    u = rng.uniform(-50, 50, (samples, m))
    return q, qd, qdd, u


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.parent.name)
def test_the_core_evaluates_each_example_as_the_model_does(path):
    model = read_model(path)
    q, qd, qdd, u = random_log(model)
    Y_c, r_c = evaluate_program(compile_program(model), q, qd, qdd, u)
    Y, r = model.regressor(q, qd, qdd, u)
    assert Y_c.shape == Y.shape and r_c.shape == r.shape
    np.testing.assert_allclose(Y_c, Y, rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(r_c, r, rtol=1e-13, atol=1e-12)


def test_units_and_constants_are_folded_in(tmp_path):
    text = """
[model]
coordinates = ["x"]
inputs = ["F"]
equations = ["M*der(x,2) + k*x + Fc*tanh(der(x)/v0)*sqrt(abs(der(x)/v0)) + m0*g*cos(x/L) = F*exp(-(x/L)**2)"]
[parameters]
M = { nominal = 1, unit = "g" }
k = { nominal = 1, unit = "N/mm" }
Fc = { nominal = 1, unit = "N" }
m0 = { nominal = 1, unit = "kg" }
[constants]
g = { value = 9.81, unit = "m/s^2" }
v0 = { value = 20, unit = "mm/s" }
L = { value = 300, unit = "mm" }
[units]
x = "mm"
F = "kN"
"""
    path = tmp_path / "m.toml"
    path.write_text(text)
    model = read_model(path)
    q, qd, qdd, u = random_log(model)
    Y_c, r_c = evaluate_program(compile_program(model), q, qd, qdd, u)
    Y, r = model.regressor(q, qd, qdd, u)
    np.testing.assert_allclose(Y_c, Y, rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(r_c, r, rtol=1e-13, atol=1e-12)


def test_a_term_nested_too_deep_is_refused(tmp_path):
    nested = "x"
    for _ in range(MAX_STACK + 2):
        nested = f"x*(x + {nested})"
    path = tmp_path / "deep.toml"
    path.write_text(f'[model]\ncoordinates = ["x"]\ninputs = ["F"]\n'
                    f'equations = ["M*der(x,2) + c*sin({nested}) = F"]\n'
                    f'[parameters]\nM = {{ nominal = 1 }}\nc = {{ nominal = 1 }}\n')
    with pytest.raises(ProgramError, match=r"equation 1, the term of c nests \d+ levels deep"):
        compile_program(read_model(path))


def test_the_core_refuses_a_damaged_program():
    model = read_model(EXAMPLES[0])
    text = compile_program(model).replace("entry 0 0", "entry 0 9", 1)
    q, qd, qdd, u = random_log(model, samples=3)
    with pytest.raises(ProgramError, match="entry column = 9"):
        evaluate_program(text, q, qd, qdd, u)


def test_the_parameters_names_reach_the_core_for_its_messages(tmp_path):
    """Names shorter than the core's TP_NAME_SIZE are written; a longer one leaves them all
    out (the FMU then says theta_k), and the core refuses a name that is not one."""
    header = (REPO / "fmu/src/core/term_program.h").read_text()
    assert int(re.search(r"#define TP_NAME_SIZE (\d+)", header).group(1)) == NAME_SIZE
    model = read_model(REPO / "examples" / "emps" / "emps.toml")
    text = compile_program(model)
    assert "\nnames M Fv Fc OF\n" in text
    q, qd, qdd, u = random_log(model, samples=3)
    evaluate_program(text, q, qd, qdd, u)  # the core reads it
    with pytest.raises(ProgramError, match="parameter name 'F-v' is not a name"):
        evaluate_program(text.replace("names M Fv", "names M F-v"), q, qd, qdd, u)
    long = tmp_path / "long.toml"
    long.write_text((REPO / "examples" / "emps" / "emps.toml").read_text(encoding="utf-8")
                    .replace("Fv", "F" * NAME_SIZE), encoding="utf-8")
    assert "\nnames " not in compile_program(read_model(long))
