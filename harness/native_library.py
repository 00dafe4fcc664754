"""The package's native library (the CMake target ``sto_native``), loaded by ctypes.

It holds the native master loop (native/master_loop.c) and the robot core's batch
entry points (native/robot_native.c) over the same C objects as the FMUs.  It
is compiled with the package, never at import: by ``./build.sh`` into ``harness/lib/``
of a checkout, or by pip when the package is installed.
"""
from __future__ import annotations

import ctypes
import sys
from functools import lru_cache
from pathlib import Path

LIBRARY_DIR = Path(__file__).resolve().with_name("lib")


class NativeUnavailable(RuntimeError):
    """The native library is not built, or cannot be loaded on this machine."""


def library_path() -> Path:
    """Where the native library of this platform is expected."""
    if sys.platform == "win32":
        name = "sto_native.dll"
    elif sys.platform == "darwin":
        name = "libsto_native.dylib"
    else:
        name = "libsto_native.so"
    return LIBRARY_DIR / name


@lru_cache(maxsize=1)
def load_library() -> ctypes.CDLL:
    """Load the native library once; `NativeUnavailable` names what is missing."""
    path = library_path()
    if not path.exists():
        raise NativeUnavailable(
            f"the native library {path} is not built: in a checkout run ./build.sh fmus, "
            "else reinstall the package (pip builds it)")
    try:
        return ctypes.CDLL(str(path))
    except OSError as error:
        raise NativeUnavailable(f"cannot load {path}: {error}") from error
