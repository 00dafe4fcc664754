"""The FMUs the project builds, read from the one place that lists them (STO_MODELS in
cmake/sources.cmake), for the scripts and tests that go over every FMU.

    python -m tools.fmu_models      prints them, separated by spaces (for the shell scripts)
"""
from __future__ import annotations

import re
from pathlib import Path

SOURCES = Path(__file__).resolve().parents[1] / "cmake" / "sources.cmake"


def models() -> tuple[str, ...]:
    """The model identifiers of STO_MODELS, in its order."""
    match = re.search(r"^set\(STO_MODELS ([^)]*)\)", SOURCES.read_text(), re.MULTILINE)
    if match is None:
        raise RuntimeError(f"{SOURCES} has no set(STO_MODELS ...)")
    return tuple(match.group(1).split())


if __name__ == "__main__":
    print(" ".join(models()))
