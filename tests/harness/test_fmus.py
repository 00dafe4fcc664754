"""harness.fmus: a value for an FMU's variable is checked against its type and declared
range before the FMU sees it; a name that is not settable is named."""
from __future__ import annotations

import pytest

from harness.fmus import FMUError, Variable, check_parameters, check_value
from harness.paths import OBSERVER, default_fmu_dir


def test_values_are_converted_to_the_variable_type():
    count = Variable("n", 1, "Integer", "parameter", 1.0, 4.0)
    assert check_value(count, "3") == 3 and isinstance(check_value(count, 2.0), int)
    with pytest.raises(FMUError, match=r"at start: n = 5 is out of range \[1, 4\]"):
        check_value(count, 5, where="at start: ")
    flag = Variable("on", 2, "Boolean", "parameter")
    assert check_value(flag, "true") is True
    with pytest.raises(FMUError, match="is not finite"):
        check_value(Variable("h", 3, "Real", "parameter"), float("inf"))


def test_parameters_are_checked_against_the_fmus_own_description():
    fmu = default_fmu_dir() / OBSERVER
    assert check_parameters(fmu, {"n": "1"}) == {"n": 1}
    with pytest.raises(FMUError, match="has no variable named 'no_such'"):
        check_parameters(fmu, {"no_such": 1})
    with pytest.raises(FMUError, match=r"x1_hat\[1\] is an output of SuperTwistingObserver"
                                       r"\.fmu: it cannot be set"):
        check_parameters(fmu, {"x1_hat[1]": 0.0})
