"""The sweep spec's JSON Schema: valid itself, accepts the documented example, and
turns each kind of shape error into a sentence naming the entry and the problem."""
from __future__ import annotations

import json
import re

import pytest
from jsonschema import Draft202012Validator

from harness import sweep
from harness.sweep.schema import check_shape, spec_schema
from harness.sweep.spec import SpecError


def test_the_schema_is_a_valid_draft_2020_12_schema():
    Draft202012Validator.check_schema(spec_schema())


def test_the_example_in_the_help_fits_the_schema():
    example = re.search(r"\n    (\{\n.*?\n    \})\n", sweep.__doc__, re.S).group(1)
    check_shape(json.loads(example))


@pytest.mark.parametrize("data, words", [
    ({}, "the spec: 'scenario' is missing"),
    ([], "the spec = [] is not a table/object"),
    ({"scenario": "6.2", "gird": {}}, "unknown spec keys ['gird']; known: ["),
    ({"scenario": "6.2", "random": {"n": 2, "ranges": {"observer.tau": [1, 2]}, "m": 1}},
     "random: unknown keys ['m']"),
    ({"scenario": "6.2", "random": {"n": 2}}, "random: 'ranges' is missing"),
    ({"scenario": "6.2", "random": {"n": 2, "ranges": {}}}, "random.ranges is empty"),
    ({"scenario": "6.2", "random": {"n": 2, "ranges": {"observer.tau": [1, 2, 3]}}},
     'random.ranges.observer.tau: give [low, high] or {"low": .., "high": .., "scale": "log"}'),
    ({"scenario": "6.2", "random": {"n": 2, "ranges": {"observer.tau": {"low": 1}}}},
     "random.ranges.observer.tau: 'high' is missing"),
    ({"scenario": "6.2", "random": {"n": 2, "ranges": {"observer.tau": {"low": 1, "high": 2,
                                                                         "scale": "ln"}}}},
     "random.ranges.observer.tau.scale 'ln' is not one of linear, log"),
    ({"scenario": "6.2", "random": {"method": "sobol", "n": 2,
                                    "ranges": {"observer.tau": [1, 2]}}},
     "random.method 'sobol' is not one of lhs, uniform"),
    ({"scenario": "6.2", "grid": {"observer.tau": []}}, "grid.observer.tau is empty"),
    ({"scenario": "6.2", "grid": {"observer.tau": 0.1}}, "grid.observer.tau = 0.1 is not a list"),
    ({"scenario": "6.2", "points": [{"observer.tau": "x"}]},
     "points[0].observer.tau = 'x' is not a number or a Boolean"),
    ({"scenario": "6.2", "seeds": []}, "seeds is empty"),
    ({"scenario": "6.2", "seeds": [1, "2"]}, "seeds[1] = '2' is not an integer"),
    ({"scenario": "6.2", "transient": -0.5}, "transient = -0.5 must be >= 0"),
    ({"scenario": "6.2", "stop_time": 0}, "stop_time = 0 is out of range (0, 10000]"),
    ({"scenario": "6.2", "stop_time": float("inf")}, "stop_time = inf is not finite"),
])
def test_shape_errors_name_the_entry_and_the_problem(data, words):
    with pytest.raises(SpecError) as error:
        check_shape(data)
    assert words in str(error.value)
