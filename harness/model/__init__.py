"""Model files: a machine's equations of motion, linear in their unknown parameters, in TOML.

``read_model(path)`` checks the file and gives a :class:`Model` whose ``regressor`` turns
positions, velocities, accelerations and inputs into ``Y @ theta = r`` (docs/model_files.md).
"""
from __future__ import annotations

from .errors import ModelFileError
from .model import Constant, Equation, Model, Parameter
from .numeric import rms_columns
from .reader import MAX_COORDINATES, parse_model, read_model

__all__ = ["Constant", "Equation", "MAX_COORDINATES", "Model", "ModelFileError", "Parameter",
           "parse_model", "read_model", "rms_columns"]
