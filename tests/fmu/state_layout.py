"""Where a field of a model's data block lies in a serialized FMU state.

The data block is a C struct private to the model (fmu/src/models/<model>/model.c), so its
layout is asked of the compiler: a small program that includes the model file
prints offsetof and sizeof of each field (e.g. "info.blocks.first[0]").  The compiler
is the one the CMake build of the FMUs configured (build/cmake/CMakeCache.txt; $CC or
cc without that build), so the layout is the FMUs'; the result is cached per model and
field set.
"""
from __future__ import annotations

import functools
import subprocess
import tempfile
from pathlib import Path

from tools.abuse.abuse_fmi import CLOCK_SIZE, HEADER_SIZE, REPO
from tools.abuse.state_format import compiler

# model identifier -> the name of its data struct (in fmu/src/models/<identifier>/model.c)
DATA_TYPES = {
    "SuperTwistingObserver": "ObserverData",
    "RobotObserver": "RobotData",
    "ModelObserver": "ModelData",
    "Pendulum": "PendulumData",
    "TwistingController": "ControllerData",
}
DATA_OFFSET = HEADER_SIZE + CLOCK_SIZE  # the model data follows the header and the clock


@functools.cache
def _layout(model: str, fields: tuple[str, ...]) -> dict[str, tuple[int, int]]:
    data_type = DATA_TYPES[model]
    src = REPO / "fmu" / "src"
    lines = [f'#include "{src / "models" / model / "model.c"}"', "#include <stdio.h>", "int main(void) {"]
    for field in fields:
        lines.append(f'    printf("%zu %zu\\n", offsetof({data_type}, {field}), '
                     f"sizeof((({data_type} *)0)->{field}));")
    lines += ["    return 0;", "}"]
    cores = sorted(str(p) for p in (src / "core").glob("*.c"))
    with tempfile.TemporaryDirectory() as tmp:
        program, binary = Path(tmp) / "layout.c", Path(tmp) / "layout"
        program.write_text("\n".join(lines) + "\n")
        subprocess.run([compiler(), "-std=c11", "-O0", "-w", "-o", str(binary),
                        str(program), *cores, "-lm"], check=True, capture_output=True)
        out = subprocess.run([str(binary)], check=True, capture_output=True, text=True).stdout
    return {field: (DATA_OFFSET + int(a), int(b))
            for field, (a, b) in zip(fields, (line.split() for line in out.splitlines()))}


def field_location(model: str, field: str) -> tuple[int, int]:
    """(offset in the serialized state, size in bytes) of ``field`` of the model's data."""
    return _layout(model, (field,))[field]
