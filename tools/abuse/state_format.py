"""The serialized FMU state's format for the abuse tests, read from
fmu/src/instance/state_format.h: a probe library is compiled from it with the
compiler of the FMUs' CMake build, so that Python restates neither the offsets
nor the checksum."""
from __future__ import annotations

import atexit
import ctypes
import functools
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def compiler() -> str:
    """The C compiler of the FMUs' CMake build (CMAKE_C_COMPILER), else $CC or cc."""
    cache = REPO / "build" / "cmake" / "CMakeCache.txt"
    if cache.is_file():
        for line in cache.read_text(errors="replace").splitlines():
            if line.startswith("CMAKE_C_COMPILER:"):
                return line.partition("=")[2].strip()
    return os.environ.get("CC", "cc")


@functools.cache
def _probe() -> ctypes.CDLL:
    folder = tempfile.mkdtemp(prefix="state-format-")
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    suffix = ".dylib" if sys.platform == "darwin" else ".so"
    library = Path(folder) / f"state_format_probe{suffix}"
    subprocess.run([compiler(), "-std=c11", "-shared", "-fPIC", "-O1",
                    f"-I{REPO / 'fmu' / 'src' / 'instance'}", "-o", str(library),
                    str(Path(__file__).with_name("state_format_probe.c"))],
                   check=True, capture_output=True)
    probe = ctypes.CDLL(str(library))
    for function in (probe.probe_header_size, probe.probe_clock_size, probe.probe_offset):
        function.restype = ctypes.c_size_t
    probe.probe_offset.argtypes = [ctypes.c_char_p]
    probe.probe_checksum.restype = ctypes.c_uint64
    probe.probe_checksum.argtypes = [ctypes.c_char_p, ctypes.c_size_t]
    return probe


def header_size() -> int:
    """Bytes of the header in front of the clock."""
    return int(_probe().probe_header_size())


def clock_size() -> int:
    """Bytes of the clock in front of the model's data block."""
    return int(_probe().probe_clock_size())


def offset(field: str) -> int:
    """Where the field of this name of the header (StateHeader) or of the clock
    (Clock) lies in a serialized state."""
    at = int(_probe().probe_offset(field.encode()))
    if at >= 1 << 32:
        raise KeyError(f"a serialized state has no field {field!r}")
    return at


def checksum(serialized: bytes) -> int:
    """The checksum that a serialized state of these bytes carries."""
    return int(_probe().probe_checksum(serialized, len(serialized)))
