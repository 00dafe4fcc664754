"""Model files: a machine's equations of motion, linear in their unknown parameters, in TOML.

``read_model(path)`` checks the file and gives a :class:`Model` whose ``regressor`` turns
positions, velocities, accelerations and inputs into ``Y @ theta = r`` (docs/model_files.md).
Each name is loaded on first use (sympy and pint are slow to import), so a module of this
package can be imported without them.
"""
from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

# name -> the module of this package that defines it
_EXPORTS = {
    "ModelFileError": "errors", "Constant": "model", "Equation": "model", "Model": "model",
    "Parameter": "model", "rms_columns": "numeric", "MAX_COORDINATES": "reader",
    "parse_model": "reader", "read_model": "reader",
}
__all__ = ["Constant", "Equation", "MAX_COORDINATES", "Model", "ModelFileError", "Parameter",
           "parse_model", "read_model", "rms_columns"]

if TYPE_CHECKING:
    from .errors import ModelFileError
    from .model import Constant, Equation, Model, Parameter
    from .numeric import rms_columns
    from .reader import MAX_COORDINATES, parse_model, read_model


def __getattr__(name: str) -> Any:
    if name not in _EXPORTS:
        raise AttributeError(f"module 'harness.model' has no attribute {name!r}")
    value = getattr(import_module(f"{__name__}.{_EXPORTS[name]}"), name)
    globals()[name] = value  # the next access is a plain lookup
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
