"""harness.values: a user's value checked against its type and range, named when it
cannot be used (never wrapped, truncated or guessed at)."""
from __future__ import annotations

import argparse
import math

import pytest

from harness.values import (
    INT32_MAX,
    BadValue,
    argparse_type,
    boolean,
    fmi_value,
    integer,
    real,
)


@pytest.mark.parametrize("value, expected", [(3, 3), (2.0, 2), ("7", 7), (" -4 ", -4),
                                             ("2e3", 2000)])
def test_integers_from_numbers_and_text(value, expected):
    assert integer("n", value) == expected


@pytest.mark.parametrize("value, said", [
    (2.5, "is not an integer"), (math.inf, "not finite"), (True, "is not an integer"),
    ("1_000", "is not a number"), ("0x10", "is not a number"), ("two", "is not a number"),
    (INT32_MAX + 1, "is out of range [-2147483648, 2147483647]"),
    (10**400, "...(401 digits) is out of range"),
])
def test_a_bad_integer_is_named(value, said):
    with pytest.raises(BadValue, match=r"^n = .*" + said.replace("[", r"\[").replace(
            "(", r"\(").replace(")", r"\)").replace(".", r"\.")):
        integer("n", value)


def test_a_sampled_float_is_rounded_only_when_asked():
    assert integer("n", 2.6, round_floats=True) == 3


@pytest.mark.parametrize("value, bounds, said", [
    (0.0, {"low": 0.0, "low_open": True}, "must be > 0"),
    (2.0, {"high": 1.0}, "must be <= 1"),
    ("nan", {}, "is not finite"),
    (10**400, {}, "too large for a floating-point number"),
    ("1_0", {}, "is not a number"),
])
def test_a_bad_real_is_named(value, bounds, said):
    with pytest.raises(BadValue, match=said):
        real("h", value, **bounds)


@pytest.mark.parametrize("value, expected", [(True, True), ("TRUE", True), ("0", False),
                                             (1, 1), (0.0, False)])
def test_booleans(value, expected):
    assert boolean("b", value) == expected


@pytest.mark.parametrize("value", ["yes", 2, None])
def test_a_bad_boolean_is_named(value):
    with pytest.raises(BadValue, match="is not a Boolean"):
        boolean("b", value)


def test_fmi_values_follow_the_variable_type_and_range():
    assert fmi_value("k", "Integer", "5", low=0, high=10) == 5
    assert fmi_value("x", "Real", 0.5, low=0.0, high=1.0) == 0.5
    with pytest.raises(BadValue, match=r"out of range \[0, 10\]"):
        fmi_value("k", "Integer", 11, low=0, high=10)
    with pytest.raises(BadValue, match="type String cannot be set"):
        fmi_value("s", "String", "a")


def test_argparse_types_turn_a_bad_value_into_a_usage_error():
    parse = argparse_type(real, "--noise", low=0.0)
    assert parse("0.25") == 0.25
    with pytest.raises(argparse.ArgumentTypeError, match="--noise = -1.0 must be >= 0"):
        parse("-1")
