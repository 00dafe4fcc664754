"""A model file written back: the same model with new nominal values (identified.toml)."""
from __future__ import annotations

import json
from collections.abc import Sequence

import numpy as np

from ..names import plain
from .model import Model, Parameter


def _string(text: str) -> str:
    """A TOML basic string (JSON's escapes are TOML's); the characters JSON leaves as
    they are but TOML does not take raw (DEL, line separators) escaped too."""
    quoted = json.dumps(text, ensure_ascii=False)
    if quoted.isprintable():
        return quoted
    return "".join(c if c.isprintable() else
                   f"\\u{ord(c):04x}" if ord(c) <= 0xFFFF else f"\\U{ord(c):08x}"
                   for c in quoted)


def _number(value: float) -> str:
    return repr(float(value))


def _range(p: Parameter) -> str:
    """The declared range as the file wrote it (positive = true for [0, inf])."""
    if not p.bounded:
        return ""
    if p.lower == 0.0 and p.upper == float("inf"):
        return ", positive = true"
    return f", range = [{_number(p.lower)}, {_number(p.upper)}]"


def model_toml(model: Model, values: Sequence[float] | np.ndarray,
               std_errors: Sequence[float] | np.ndarray | None = None,
               header: Sequence[str] = ()) -> str:
    """The TOML text of ``model`` with ``values`` (in the order of its parameters) as the
    nominal values; the standard errors, if given, as comments. ``read_model`` reads it
    back to the same model."""
    lines = [f"# {plain(line)}" for line in header]  # a comment is one line
    lines += ["[model]", f"coordinates = [{', '.join(_string(c) for c in model.coordinates)}]",
              f"inputs = [{', '.join(_string(u) for u in model.inputs)}]",
              "equations = [", *(f"    {_string(e.text)}," for e in model.equations), "]", "",
              "[parameters]"]
    width = max(len(p.name) for p in model.parameters)
    for k, p in enumerate(model.parameters):
        flags = (", optional = true" if p.optional else "") + _range(p)
        entry = (f"{p.name:<{width}} = {{ nominal = {_number(values[k])}, "
                 f"unit = {_string(p.unit)}{flags} }}")
        if std_errors is not None:
            entry += f"   # std error {float(std_errors[k]):.3g}"
        lines.append(entry)
    if model.constants:
        lines += ["", "[constants]"]
        lines += [f"{k.name} = {{ value = {_number(k.value)}, unit = {_string(k.unit)} }}"
                  for k in model.constants]
    if model.units or model.time_unit is not None:
        lines += ["", "[units]"]
        lines += [f"t = {_string(model.time_unit)}"] if model.time_unit is not None else []
        lines += [f"{name} = {_string(unit)}" for name, unit in model.units.items()]
    log = ([f"sample_rate = {_number(model.sample_rate)}"] if model.sample_rate is not None
           else []) + ([f"inputs = {_string(model.input_timing)}"]
                       if model.input_timing is not None else [])
    if log:
        lines += ["", "[log]", *log]
    lines += ["", "[columns]"]
    lines += [f"{name} = {_string(column)}" for name, column in model.columns.items()]
    return "\n".join(lines) + "\n"
