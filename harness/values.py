"""Checking values that users give (command line, sweep specs, --param) before use.

Every function returns the value in the type it will be used as, or raises
:class:`BadValue` with a message that names the value and says what is
wrong: a value never wraps (4294967298 as a 32-bit Integer is 2), truncates
(1.5 as an Integer is 1) or turns into NaN silently.
"""
from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from typing import Any

INT32_MIN, INT32_MAX = -2**31, 2**31 - 1


class BadValue(ValueError):
    """A user-given value cannot be used; the message names it and says why."""


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _bounds_text(low: float | None, high: float | None) -> str:
    def text(x: float) -> str:
        return str(int(x)) if float(x).is_integer() and abs(x) < 2**63 else f"{x:g}"
    return f"[{'-inf' if low is None else text(low)}, {'inf' if high is None else text(high)}]"


def integer(name: str, value: Any, low: int | None = INT32_MIN, high: int | None = INT32_MAX,
            round_floats: bool = False) -> int:
    """``value`` as an int in [low, high] (FMI Integers are 32-bit: the default).

    Accepts ints and integral floats (2.0); a non-integral float is an error unless
    ``round_floats`` (a value sampled from a range).  Strings are parsed."""
    if isinstance(value, str):
        value = _parse_number(name, value)
    if not _is_number(value):
        raise BadValue(f"{name} = {value!r} is not an integer")
    if isinstance(value, float):
        if not math.isfinite(value):
            raise BadValue(f"{name} = {value!r} is not an integer (not finite)")
        if not value.is_integer():
            if not round_floats:
                raise BadValue(f"{name} = {value!r} is not an integer")
            value = round(value)
        value = int(value)
    if (low is not None and value < low) or (high is not None and value > high):
        raise BadValue(f"{name} = {_short(value)} is out of range {_bounds_text(low, high)}")
    return value


def real(name: str, value: Any, low: float | None = None, high: float | None = None, *,
         low_open: bool = False, high_open: bool = False) -> float:
    """``value`` as a finite float in the range (open ends where said)."""
    if isinstance(value, str):
        value = _parse_number(name, value)
    if not _is_number(value):
        raise BadValue(f"{name} = {value!r} is not a number")
    try:
        number = float(value)
    except OverflowError:
        raise BadValue(f"{name} = {_short(value)} is too large for a floating-point "
                       "number") from None
    if not math.isfinite(number):
        raise BadValue(f"{name} = {value!r} is not finite")
    if low is not None and (number <= low if low_open else number < low):
        raise BadValue(f"{name} = {number!r} must be {'>' if low_open else '>='} {low:g}")
    if high is not None and (number >= high if high_open else number > high):
        raise BadValue(f"{name} = {number!r} must be {'<' if high_open else '<='} {high:g}")
    return number


def boolean(name: str, value: Any) -> bool:
    """True/False, 1/0 (numbers or text), "true"/"false" (any case)."""
    if isinstance(value, bool):
        return value
    if isinstance(value, str):
        lowered = value.strip().lower()
        if lowered in ("true", "1"):
            return True
        if lowered in ("false", "0"):
            return False
    elif _is_number(value) and value in (0, 1):
        return bool(value)
    raise BadValue(f"{name} = {value!r} is not a Boolean (true/false or 1/0)")


def fmi_value(name: str, type_: str, value: Any, low: float | None = None,
              high: float | None = None, round_floats: bool = False) -> float | int | bool:
    """A value for an FMU variable of FMI type ``type_`` ("Real", "Integer",
    "Boolean") with the declared range [low, high] (None: unbounded)."""
    if type_ == "Boolean":
        return boolean(name, value)
    if type_ == "Integer":
        lo = INT32_MIN if low is None else max(INT32_MIN, int(low))
        hi = INT32_MAX if high is None else min(INT32_MAX, int(high))
        return integer(name, value, lo, hi, round_floats=round_floats)
    if type_ == "Real":
        return real(name, value, low, high)
    raise BadValue(f"{name}: variables of type {type_} cannot be set")


def _parse_number(name: str, text: str) -> int | float:
    stripped = text.strip()
    if "_" in stripped:  # Python reads "1_000" as 1000: a typo is not guessed at
        raise BadValue(f"{name} = {text!r} is not a number")
    try:
        return int(stripped)
    except ValueError:
        pass
    try:
        return float(stripped)
    except ValueError:
        raise BadValue(f"{name} = {text!r} is not a number") from None


def _short(value: Any) -> str:
    text = str(value)
    return text if len(text) <= 40 else f"{text[:20]}...({len(text)} digits)"


def argparse_type(check: Callable[..., Any], name: str, **bounds: Any) -> Callable[[str], Any]:
    """An argparse ``type=`` that applies ``check`` (integer, real, ...): a bad value
    becomes argparse's usage error (exit status 2), not a traceback."""
    def parse(text: str) -> Any:
        try:
            return check(name, text, **bounds)
        except BadValue as error:
            raise argparse.ArgumentTypeError(str(error)) from None
    parse.__name__ = name  # argparse names the type in some messages
    return parse
