"""A one-coordinate model file for the model path's tests: a mass M with viscous friction
Fv pushed by F, its equation, coordinate and extra lines replaceable."""
from __future__ import annotations

from pathlib import Path

MODEL = '''[model]
coordinates = ["{c}"]
inputs = ["F"]
equations = ["{eq}"]

[parameters]
M = {{ nominal = 1 }}
Fv = {{ nominal = 1 }}
{extra}'''


def model(path: Path, eq: str = "M*der(x,2) + Fv*der(x) = F", c: str = "x",
          extra: str = "") -> Path:
    path.write_text(MODEL.format(c=c, eq=eq, extra=extra), encoding="utf-8")
    return path
