"""The JSON files the tools write: strict JSON (RFC 8259), which every reader takes.

Python's json writes NaN and Infinity, which are not JSON: a figure that is not a finite
number is written as null instead, and said by name (a warning: the command then exits 1),
never passed off as a number.
"""
from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any


def _finite(value: Any, where: str, nulls: list[str]) -> Any:
    """``value`` with every non-finite float replaced by None; their places in ``nulls``."""
    if isinstance(value, float):
        if math.isfinite(value):
            return value
        nulls.append(f"{where} ({value})" if where else str(value))
        return None
    if isinstance(value, dict):
        return {k: _finite(v, f"{where}.{k}" if where else str(k), nulls)
                for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v, f"{where}[{i}]", nulls) for i, v in enumerate(value)]
    return value


def strict_json(data: Any, indent: int | None = 2,
                default: Callable[[Any], Any] | None = None) -> tuple[str, list[str]]:
    """The JSON text of ``data`` (non-finite numbers as null) and the places of those
    numbers (``relative_error.pooled (nan)``)."""
    nulls: list[str] = []
    text = json.dumps(_finite(data, "", nulls), indent=indent, allow_nan=False,
                      default=default)
    return text + "\n", nulls


def write_json(path: Path, data: Any, indent: int | None = 2,
               default: Callable[[Any], Any] | None = None, warn: bool = True) -> None:
    """Writes ``data`` to ``path`` as strict JSON; each non-finite figure is written as null
    and named in a warning (``warn=False``: where null is a documented value, a settling
    time that is never reached)."""
    from .messages import note

    text, nulls = strict_json(data, indent, default)
    Path(path).write_text(text, encoding="utf-8")
    for place in nulls if warn else ():
        note(f"{Path(path).name}: {place} is not a finite number, written as null")
