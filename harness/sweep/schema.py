"""The JSON Schema of a sweep specification, and its check with clear messages.

The schema (:func:`spec_schema`, JSON Schema draft 2020-12; print it with
``python -m harness.sweep.schema``) fixes the shape of a spec: which keys,
their types, the choices of "scenario", "method", "random.method" and
"scale", and the bounds of stop_time, transient, random.n, random.seed and
seeds.  What a schema cannot say is checked afterwards by harness.sweep.plan
and harness.sweep.spec: that a parameter names a variable of an FMU, its
value fits that variable's type and declared range, numbers are finite
(JSON parsers accept NaN and Infinity), and the number of runs.

:func:`check_shape` raises a SpecError naming the entry (``random.n``,
``points[2].observer.tau``), the value and what it must be; huge numbers
are shown as "a huge number".
"""
from __future__ import annotations

import json
import math
from collections.abc import Sequence
from functools import lru_cache
from typing import Any

from .spec import MAX_RUNS, MAX_STOP_TIME, SEED_MAX, SpecError

METHODS = ("paper", "improved")
TYPE_WORDS = {"object": "a table/object", "array": "a list", "number": "a number",
              "integer": "an integer", "string": "a string", "boolean": "a Boolean"}
RUN_LIMIT = f"a sweep has at most {MAX_RUNS} runs (harness.sweep.spec.MAX_RUNS)"
HUGE = 10**40  # integers from here on are shown as "a huge number"


@lru_cache(maxsize=1)
def spec_schema() -> dict[str, Any]:
    """The JSON Schema of a sweep spec (a new dict each process; do not modify)."""
    from ..scenarios import SCENARIOS

    value = {"type": ["number", "boolean"],
             "description": "a parameter value: a number (Real, Integer) or true/false (Boolean)"}
    values = {"type": "object", "additionalProperties": {"$ref": "#/$defs/value"},
              "description": "parameter -> value; a parameter is 'fmu.variable' (fmu: plant, "
                             "controller, observer) or noise_std or seed"}
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "harness sweep specification",
        "description": "The closed-loop runs of one sweep: (grid x random samples) + points, "
                       "each x seeds (see python -m harness sweep --help).",
        "type": "object",
        "required": ["scenario"],
        "additionalProperties": False,
        "properties": {
            "description": {"type": "string", "description": "free text, ignored"},
            "scenario": {"enum": list(SCENARIOS), "description": "the scenario to sweep"},
            "stop_time": {"type": "number", "exclusiveMinimum": 0, "maximum": int(MAX_STOP_TIME),
                          "description": "the runs' length [s] (default: the scenario's)"},
            "transient": {"type": "number", "minimum": 0,
                          "description": "the metrics' transient [s] (default: the scenario's)"},
            "method": {"enum": list(METHODS),
                       "description": "paper: the scenario as is; improved: the FMU's defaults"},
            "fixed": {**values, "description": "the same value in every run"},
            "grid": {"type": "object",
                     "additionalProperties": {"type": "array", "minItems": 1,
                                              "items": {"$ref": "#/$defs/value"}},
                     "description": "parameter -> list of values: their cartesian product"},
            "random": {
                "type": "object", "additionalProperties": False, "required": ["n", "ranges"],
                "description": "n samples of the ranges, crossed with the grid",
                "properties": {
                    "method": {"enum": ["lhs", "uniform"],
                               "description": "lhs: Latin hypercube (default); uniform"},
                    "n": {"type": "integer", "minimum": 1, "maximum": MAX_RUNS,
                          "description": "samples", "$comment": RUN_LIMIT},
                    "seed": {"type": "integer", "minimum": 0, "maximum": SEED_MAX,
                             "description": "the sampling seed (default 0)"},
                    "ranges": {"type": "object", "minProperties": 1,
                               "additionalProperties": {"$ref": "#/$defs/range"},
                               "description": "parameter -> its range"}}},
            "points": {"type": "array", "items": values,
                       "description": "extra runs, each a table of parameter values"},
            "seeds": {"type": ["integer", "array"], "minimum": 1, "maximum": MAX_RUNS,
                      "minItems": 1,
                      "items": {"type": "integer", "minimum": 0, "maximum": SEED_MAX},
                      "description": "noise seeds, or a count n for seeds 0 .. n-1",
                      "$comment": RUN_LIMIT},
        },
        "$defs": {
            "value": value,
            "range": {
                "type": ["array", "object"],
                "description": "[low, high] (uniform), or {low, high, scale: linear | log}",
                "prefixItems": [{"type": "number"}, {"type": "number"}],
                "minItems": 2, "maxItems": 2,
                "required": ["low", "high"], "additionalProperties": False,
                "properties": {"low": {"type": "number"}, "high": {"type": "number"},
                               "scale": {"enum": ["linear", "log"]}}},
        },
    }


@lru_cache(maxsize=1)
def _validator():
    from jsonschema import Draft202012Validator

    return Draft202012Validator(spec_schema())


def check_shape(data: Any) -> None:
    """SpecError for the first way ``data`` does not fit :func:`spec_schema`."""
    errors = sorted(_validator().iter_errors(data),
                    key=lambda e: (len(e.absolute_path), [str(p) for p in e.absolute_path]))
    if errors:
        raise SpecError(message(errors[0]))


def _where(path: Sequence[Any]) -> str:
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


def _shown(value: Any) -> str:
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= HUGE:
        return "a huge number"
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else str(value)
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _bounds(schema: dict[str, Any]) -> str:
    low = schema.get("minimum", schema.get("exclusiveMinimum"))
    high = schema.get("maximum", schema.get("exclusiveMaximum"))
    if low is not None and high is not None:
        return (f"is out of range {'(' if 'exclusiveMinimum' in schema else '['}{low}, "
                f"{high}{')' if 'exclusiveMaximum' in schema else ']'}")
    if low is not None:
        return f"must be {'>' if 'exclusiveMinimum' in schema else '>='} {low}"
    return f"must be {'<' if 'exclusiveMaximum' in schema else '<='} {high}"


def message(error) -> str:
    """A jsonschema ValidationError as a sentence naming the entry and the problem."""
    where = _where(error.absolute_path)
    value = error.instance
    schema = error.schema if isinstance(error.schema, dict) else {}
    note = f": {schema['$comment']}" if "$comment" in schema else ""  # why the bound
    kind = error.validator
    if kind == "additionalProperties":
        extra = sorted(set(value) - set(schema.get("properties", {})))
        known = sorted(schema.get("properties", {}))
        return (f"unknown spec keys {extra}; known: {known}" if not where
                else f"{where}: unknown keys {extra}; known: {known}")
    if kind == "required":
        missing = [k for k in schema["required"] if k not in value]
        return f"{where or 'the spec'}: {', '.join(repr(k) for k in missing)} is missing"
    if kind == "type":
        types = schema["type"] if isinstance(schema["type"], list) else [schema["type"]]
        return (f"{where or 'the spec'} = {_shown(value)} is not "
                f"{' or '.join(TYPE_WORDS[t] for t in types)}")
    if kind == "enum":
        return f"{where} {_shown(value)} is not one of {', '.join(map(str, schema['enum']))}"
    if kind in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"):
        if isinstance(value, float) and not math.isfinite(value):
            return f"{where} = {value} is not finite"
        return f"{where} = {_shown(value)} {_bounds(schema)}{note}"
    if kind in ("minItems", "maxItems") and "prefixItems" in schema:  # a random range
        return f"{where}: give [low, high] or {{\"low\": .., \"high\": .., \"scale\": \"log\"}}"
    if kind in ("minItems", "minProperties"):
        return f"{where} is empty"
    return f"{where or 'the spec'}: {error.message}"


def main() -> int:
    print(json.dumps(spec_schema(), indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
