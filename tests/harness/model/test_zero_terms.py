"""An unknown whose term is identically zero (it cancels out) is refused by name with exit
status 2; a term that is nearly but not zero is kept (harness/model/zero_terms.py)."""
from __future__ import annotations

import pytest
from cli_runner import cli, refused
from model_text import model

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


@pytest.mark.parametrize("term", ["K*(sin(x)^2 + cos(x)^2 - 1)", "K*(cosh(x)^2 - sinh(x)^2 - 1)",
                                  "K*((x+1)^2 - x^2 - 2*x - 1)*der(x)"])
def test_an_unknown_whose_term_is_identically_zero_is_refused_by_name(tmp_path, term):
    path = model(tmp_path / "m.toml", f"M*der(x,2) + Fv*der(x) + {term} = F",
                 extra="K = { nominal = 1 }\n")
    code, text = cli(["fmu", "--model", str(path), "--out", str(tmp_path / "out")])
    assert code == 2, text
    refused(code, text, str(path), "K", "cancel out")


def test_a_term_that_is_nearly_but_not_zero_is_kept(tmp_path):
    from harness.model import read_model
    read_model(model(tmp_path / "m.toml", "M*der(x,2) + Fv*der(x) + "
                     "K*(sin(x)^2 + cos(x)^2 - 0.999999) = F", extra="K = { nominal = 1 }\n"))
