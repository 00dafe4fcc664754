"""Read a model file (TOML) into a checked :class:`Model`."""
from __future__ import annotations

import keyword
import math
import re
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10
    import tomli as tomllib

import sympy

from ..inputs import InputError, check_toml_nesting, read_text
from ..units import factor
from .errors import ModelFileError
from .expressions import RESERVED, ExpressionError, Symbols, free_names, parse_equation
from .linear import check_accelerations, split_linear
from .model import INPUT_TIMINGS, Constant, Equation, Model, Parameter
from .units import check_equation, quantity
from .zero_terms import cancelled

#: Most coordinates a model may have (the FMUs' fixed sizes).
MAX_COORDINATES = 7
#: Bytes of a model file: one is a few kilobytes; every byte becomes sympy work.
MAX_MODEL_BYTES = 1 << 20
#: Parameters, and constants, a model may declare: the model FMU holds 32 parameters and
#: 512 constants; each name is a sympy symbol in every equation's namespace.
MAX_PARAMETERS = 256
MAX_CONSTANTS = 1024
SECTIONS = {"model": True, "parameters": True, "constants": False, "units": False,
            "columns": False, "log": False}
_MODEL_KEYS = {"coordinates", "inputs", "equations"}
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
TIME = "t"
#: Builds the error for a problem, with the file named.
Fail = Callable[[str], ModelFileError]


def read_model(path: str | Path) -> Model:
    """Read and check the model file at ``path``; raises :class:`ModelFileError`."""
    path = Path(path)
    try:  # read with a cap: a device (/dev/zero) claims a size of 0 and has no end
        text = read_text(path, "model file", limit=MAX_MODEL_BYTES)
    except InputError as exc:
        problem = str(exc).removeprefix(f"{path}: ").removeprefix(f"{path} ")
        raise ModelFileError(path, problem.replace("cannot read the model file",
                                                   "cannot be read")) from None
    return parse_model(text, source=path)


def parse_model(text: str, source: str | Path | None = None) -> Model:
    """Check and build the model of TOML ``text``; ``source`` names it in error messages."""
    def fail(problem: str) -> ModelFileError:
        return ModelFileError(source, problem)

    if len(text) > MAX_MODEL_BYTES:
        raise fail(f"is {len(text)} characters long; a model file has at most "
                   f"{MAX_MODEL_BYTES}")
    nesting = check_toml_nesting(text)  # before the TOML parser recurses into it
    if nesting is not None:
        raise fail(f"is not a model file: {nesting}")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise fail(f"is not valid TOML: {exc}") from None
    except (RecursionError, MemoryError):  # beyond what the scan above lets through
        raise fail("is not a model file: nested too deeply") from None
    for section in data:
        if section not in SECTIONS:
            raise fail(f"has an unknown section [{section}] (known: "
                       + ", ".join(f"[{s}]" for s in SECTIONS) + ")")
    for section, required in SECTIONS.items():
        if section not in data:
            if required:
                raise fail(f"has no [{section}] section")
            continue
        if not isinstance(data[section], dict):
            raise fail(f"[{section}] must be a table")
    model = data["model"]
    unknown = set(model) - _MODEL_KEYS
    if unknown:
        raise fail(f"[model] has unknown keys {sorted(unknown)} (known: {sorted(_MODEL_KEYS)})")
    coordinates = _names(model, "coordinates", fail, required=True)
    inputs = _names(model, "inputs", fail, required=False)
    if not 1 <= len(coordinates) <= MAX_COORDINATES:
        raise fail(f"declares {len(coordinates)} coordinates; a model has 1 to "
                   f"{MAX_COORDINATES}")
    for section, most in (("parameters", MAX_PARAMETERS), ("constants", MAX_CONSTANTS)):
        if len(data.get(section, {})) > most:
            raise fail(f"[{section}] declares {len(data[section])} names; at most {most}")
    parameters = [_parameter(name, spec, fail) for name, spec in data["parameters"].items()]
    if not parameters:
        raise fail("[parameters] is empty: declare at least one unknown to identify")
    constants = [_constant(name, spec, fail) for name, spec in data.get("constants", {}).items()]
    _check_names(coordinates, inputs, [p.name for p in parameters],
                 [k.name for k in constants], fail)

    symbols = Symbols.of(coordinates, inputs, [p.name for p in parameters],
                         [k.name for k in constants])
    unit_table, time_unit = data.get("units"), None
    if unit_table is not None and TIME in unit_table:  # the log's time column
        unit_table = {k: v for k, v in unit_table.items() if k != TIME}
        time_unit = _time_unit(data["units"][TIME], fail)
        unit_table = unit_table or None  # t alone: nothing else scaled or checked
    units = _units(unit_table, coordinates, inputs, parameters, constants, fail)
    columns = _columns(data.get("columns", {}), coordinates, inputs, fail)
    sample_rate, input_timing = _log_settings(data.get("log", {}), fail)
    equations = _equations(model, coordinates, symbols, units,
                           {p.name: p.unit for p in parameters},
                           {k.name: k.unit for k in constants}, fail)
    used = set().union(*(free_names(e.residual, symbols.parameters) for e in equations))
    unused = [p.name for p in parameters if p.name not in used]
    if unused:
        raise fail(f"parameter(s) {', '.join(unused)} appear in no equation")
    values = {symbols.constants[k.name]: sympy.Float(k.value) for k in constants}
    zero = cancelled(((p.name, [e.terms[k].xreplace(values) for e in equations])
                      for k, p in enumerate(parameters)), symbols.measured())
    if zero:
        raise fail(f"parameter(s) {', '.join(zero)} cancel out: the term of each is "
                   "identically zero (e.g. sin(x)^2 + cos(x)^2 - 1), so no log could "
                   "identify it; remove it or write the term it stands for")
    return Model(str(source) if source is not None else "<model>", tuple(coordinates),
                 tuple(inputs), tuple(parameters), tuple(constants), units, columns,
                 tuple(equations), symbols, time_unit, sample_rate, input_timing)


def _names(model: Mapping[str, Any], key: str, fail: Fail, required: bool) -> list[str]:
    if key not in model:
        if required:
            raise fail(f"[model] has no '{key}' list")
        return []
    names = model[key]
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise fail(f"[model] {key} must be a list of names")
    if len(names) > MAX_PARAMETERS:
        raise fail(f"[model] {key} has {len(names)} names; at most {MAX_PARAMETERS}")
    return names


def _number(value: Any, what: str, fail: Fail) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise fail(f"{what} must be a number, not {value!r}")
    number = _as_float(value, what, fail)
    if not math.isfinite(number):
        raise fail(f"{what} must be finite, not {value}")
    return number


def _as_float(value: int | float, what: str, fail: Fail) -> float:
    """A TOML number as a float; TOML integers have any size, a float64 ends at 1.8e308."""
    try:
        return float(value)
    except OverflowError:
        bits = int(value).bit_length()  # only an int overflows float()
        raise fail(f"{what} is an integer of {bits} bits, beyond a float64's range (about "
                   "1.8e308)") from None


def _unit(unit: Any, what: str, fail: Fail) -> str:
    if not isinstance(unit, str):
        raise fail(f"the unit of {what} must be a string, not {unit!r}")
    try:
        quantity(unit)
    except ValueError as exc:
        raise fail(f"the unit of {what}: {exc}") from None
    return unit


def _parameter(name: str, spec: Any, fail: Fail) -> Parameter:
    if not isinstance(spec, dict):
        raise fail(f"parameter {name} must be a table such as "
                   f"{name} = {{ nominal = 1.0, unit = \"kg\" }}")
    unknown = set(spec) - {"nominal", "unit", "optional", "positive", "range"}
    if unknown:
        raise fail(f"parameter {name} has unknown keys {sorted(unknown)} (known: nominal, "
                   "unit, optional, positive, range)")
    if "nominal" not in spec:
        raise fail(f"parameter {name} has no nominal value")
    nominal = _number(spec["nominal"], f"the nominal value of parameter {name}", fail)
    unit = _unit(spec.get("unit", ""), f"parameter {name}", fail)
    flags = {}
    for key in ("optional", "positive"):
        flags[key] = spec.get(key, False)
        if not isinstance(flags[key], bool):
            raise fail(f"parameter {name}: {key} must be true or false, not {flags[key]!r}")
    lower, upper = _range(name, spec, flags["positive"], fail)
    if not lower <= nominal <= upper:
        raise fail(f"parameter {name}: the nominal value {nominal:g} is outside its declared "
                   f"range [{lower:g}, {upper:g}]")
    if flags["optional"] and not lower <= 0.0 <= upper:
        raise fail(f"parameter {name}: optional means it may be left out at 0, which is "
                   f"outside its declared range [{lower:g}, {upper:g}]")
    return Parameter(name, nominal, unit, flags["optional"], lower, upper)


def _range(name: str, spec: dict, positive: bool, fail: Fail) -> tuple[float, float]:
    """``positive = true`` is the range [0, inf]; ``range = [a, b]`` (a < b, either may be
    -inf or inf as TOML writes them) any other; not both."""
    if "range" not in spec:
        return (0.0 if positive else -math.inf), math.inf
    if positive:
        raise fail(f"parameter {name}: give positive = true or range = [a, b], not both")
    bounds = spec["range"]
    if not (isinstance(bounds, list) and len(bounds) == 2):
        raise fail(f"parameter {name}: range must be a list [lower, upper], not {bounds!r}")
    lower, upper = bounds
    ends = []
    for value, what in ((lower, "lower"), (upper, "upper")):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or (
                isinstance(value, float) and math.isnan(value)):
            raise fail(f"parameter {name}: the {what} end of its range must be a number "
                       f"(inf and -inf allowed), not {value!r}")
        ends.append(_as_float(value, f"parameter {name}: the {what} end of its range", fail))
    if not ends[0] < ends[1]:
        raise fail(f"parameter {name}: range = [{ends[0]:g}, {ends[1]:g}] is empty (lower "
                   "must be below upper)")
    return ends[0], ends[1]


def _constant(name: str, spec: Any, fail: Fail) -> Constant:
    if isinstance(spec, dict):
        unknown = set(spec) - {"value", "unit"}
        if unknown or "value" not in spec:
            raise fail(f"constant {name} must be a number or a table "
                       "{ value = ..., unit = \"...\" }")
        return Constant(name, _number(spec["value"], f"constant {name}", fail),
                        _unit(spec.get("unit", ""), f"constant {name}", fail))
    return Constant(name, _number(spec, f"constant {name}", fail))


def _check_names(coordinates: list[str], inputs: list[str], parameters: list[str],
                 constants: list[str], fail: Fail) -> None:
    seen: dict[str, str] = {}
    for kind, names in (("coordinate", coordinates), ("input", inputs),
                        ("parameter", parameters), ("constant", constants)):
        for name in names:
            if not _NAME.fullmatch(name) or keyword.iskeyword(name):
                raise fail(f"{kind} name '{name}' is not a name (a letter, then letters, "
                           "digits or _)")
            if name in RESERVED:
                raise fail(f"{kind} name '{name}' is reserved (" + ", ".join(sorted(RESERVED))
                           + ")")
            if name in seen:
                raise fail(f"the name '{name}' is used twice: as {seen[name]} and as {kind}")
            seen[name] = kind


def _time_unit(unit: Any, fail: Fail) -> str:
    """[units] t: the unit of the log's time column, a unit of time."""
    unit = _unit(unit, "t (the log's time column)", fail)
    try:
        factor(unit, "s")
    except ValueError as exc:
        raise fail(f"[units] t: {exc} (the log's time column: s, ms, us, ...)") from None
    return unit


def _units(table: Any, coordinates: list[str], inputs: list[str],
           parameters: list[Parameter], constants: list[Constant],
           fail: Fail) -> dict[str, str]:
    """The [units] table (t taken out), complete for coordinates and inputs, or {}
    without one."""
    if table is None:
        return {}
    unknown = set(table) - set(coordinates) - set(inputs)
    if unknown:
        raise fail(f"[units] names {sorted(unknown)}, which are not coordinates or inputs "
                   "(parameters and constants carry their unit themselves)")
    missing = [n for n in (*coordinates, *inputs) if n not in table]
    if missing:
        raise fail(f"[units] gives no unit for {', '.join(missing)}: with [units], every "
                   "coordinate and input needs one")
    without = [p.name for p in parameters if not p.unit]
    if without:
        raise fail(f"parameter(s) {', '.join(without)} have no unit, which the dimension "
                   "check of [units] needs (write unit = \"1\" for a dimensionless one)")
    return {name: _unit(table[name], name, fail) for name in (*coordinates, *inputs)}


def _log_settings(table: Any, fail: Fail) -> tuple[float | None, str | None]:
    """[log] sample_rate [Hz]: the log's samples are evenly spaced at this rate, and its
    time column (if any) is not read; [log] inputs: "held" (each input sample acts until
    the next, as a digital controller's output does) or "sampled" (samples of a
    continuous signal); absent: identify chooses by the data."""
    unknown = set(table) - {"sample_rate", "inputs"}
    if unknown:
        raise fail(f"[log] has unknown keys {sorted(unknown)} (known: sample_rate, inputs)")
    timing = table.get("inputs")
    if timing is not None and timing not in INPUT_TIMINGS:
        raise fail(f"[log] inputs must be one of {', '.join(map(repr, INPUT_TIMINGS))}, "
                   f"not {timing!r}")
    if "sample_rate" not in table:
        return None, timing
    rate = _number(table["sample_rate"], "[log] sample_rate", fail)
    if not rate > 0.0:
        raise fail(f"[log] sample_rate must be > 0 (samples per second), not {rate}")
    return rate, timing


def _columns(table: Any, coordinates: list[str], inputs: list[str],
             fail: Fail) -> dict[str, str]:
    """Each coordinate's, input's and the time's log column; a name's default is itself."""
    known = {TIME, *coordinates, *inputs}
    unknown = set(table) - known
    if unknown:
        raise fail(f"[columns] maps {sorted(unknown)}, which are not t, a coordinate or an "
                   "input")
    columns = {name: name for name in (TIME, *coordinates, *inputs)}
    for name, column in table.items():
        if not isinstance(column, str) or not column:
            raise fail(f"[columns] {name} must be a column name, not {column!r}")
        columns[name] = column
    return columns


def _equations(model: Mapping[str, Any], coordinates: list[str], symbols: Symbols,
               units: Mapping[str, str], parameter_units: Mapping[str, str],
               constant_units: Mapping[str, str], fail: Fail) -> list[Equation]:
    texts = model.get("equations")
    if texts is None:
        raise fail("[model] has no 'equations' list")
    if not isinstance(texts, list):
        raise fail("[model] equations must be a list of strings, one per coordinate")
    if len(texts) != len(coordinates):
        raise fail(f"[model] has {len(texts)} equation(s) for {len(coordinates)} "
                   "coordinate(s): write one equation of motion per coordinate, in order")
    unit_of = _symbol_units(symbols, units, parameter_units, constant_units) if units else None
    parameters = list(symbols.parameters.values())
    accelerations = list(symbols.acceleration.values())
    equations = []
    for i, (text, coordinate) in enumerate(zip(texts, coordinates), start=1):
        shown = text if not isinstance(text, str) or len(text) <= 200 else text[:197] + "..."
        where = f"equation {i} ({shown!r})" if isinstance(text, str) and not text.isprintable() \
            else f"equation {i} ('{shown}')"
        try:
            lhs, rhs = parse_equation(text, symbols)
            residual = lhs - rhs
            if symbols.acceleration[coordinate] not in residual.free_symbols:
                raise ExpressionError(
                    f"has no der({coordinate},2): equation {i} is the equation of motion of "
                    f"coordinate {coordinate} and must contain its second derivative")
            check_accelerations(residual, accelerations)
            split = split_linear(residual, parameters)
            if unit_of is not None:
                check_equation(lhs, rhs, unit_of)
        except ExpressionError as exc:
            raise fail(f"{where} {exc}") from None
        except (RecursionError, MemoryError):  # a bound of expressions.py let it through
            raise fail(f"{where} is too large to be worked with") from None
        equations.append(Equation(text, lhs, rhs, split.terms, split.known))
    return equations


def _symbol_units(symbols: Symbols, units: Mapping[str, str],
                  parameter_units: Mapping[str, str],
                  constant_units: Mapping[str, str]) -> dict[sympy.Symbol, Any]:
    """The pint unit of every symbol, for the dimension check."""
    second = quantity("s")
    out: dict[sympy.Symbol, Any] = {}
    for c, sym in symbols.position.items():
        out[sym] = quantity(units[c])
        out[symbols.velocity[c]] = out[sym] / second
        out[symbols.acceleration[c]] = out[sym] / second ** 2
    for name, sym in symbols.inputs.items():
        out[sym] = quantity(units[name])
    for name, sym in symbols.parameters.items():
        out[sym] = quantity(parameter_units[name])
    for name, sym in symbols.constants.items():
        out[sym] = quantity(constant_units[name])  # a plain number is dimensionless
    return out
