"""The native master loop (native/master_loop.c), compiled on first use.

Shared libraries compiled by the harness (this loop, the robot core of
harness.robot.native) are cached in $STO_HARNESS_CACHE (default
~/.cache/sto-harness), keyed by a hash of their sources, headers and flags, so a
changed source is rebuilt automatically.
"""
from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
from functools import lru_cache
from pathlib import Path

SOURCE = Path(__file__).with_name("native") / "master_loop.c"
CFLAGS = ["-std=c11", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-O2", "-fPIC", "-shared"]


class NativeUnavailable(RuntimeError):
    """No C compiler, or the loop did not compile: use the Python loop."""


class LoopFMU(ctypes.Structure):
    _fields_ = [("component", ctypes.c_void_p), ("do_step", ctypes.c_void_p),
                ("get_real", ctypes.c_void_p), ("set_real", ctypes.c_void_p)]


class LoopLink(ctypes.Structure):
    _fields_ = [("source_fmu", ctypes.c_int), ("source_vr", ctypes.c_uint),
                ("source_signal", ctypes.c_int), ("noise_signal", ctypes.c_int),
                ("target_fmu", ctypes.c_int), ("target_vr", ctypes.c_uint)]


class LoopProbe(ctypes.Structure):
    _fields_ = [("fmu", ctypes.c_int), ("vr", ctypes.c_uint)]


class LoopFailure(ctypes.Structure):
    _fields_ = [("step", ctypes.c_long), ("fmu", ctypes.c_int), ("call", ctypes.c_int),
                ("status", ctypes.c_int)]


def cache_dir() -> Path:
    return Path(os.environ.get("STO_HARNESS_CACHE", Path.home() / ".cache" / "sto-harness"))


def compile_library(name: str, sources: list[Path], include: Path | None = None) -> Path:
    """Compile `sources` (with the headers of `include`) into a cached shared library,
    rebuilt when a source, a header or the flags change; NativeUnavailable if it cannot."""
    missing = [str(s) for s in sources if not s.exists()]
    if missing:
        raise NativeUnavailable(f"C sources not found: {', '.join(missing)}")
    headers = sorted(include.glob("*.h")) if include is not None else []
    digest = hashlib.sha256(b"".join(f.read_bytes() for f in [*sources, *headers]) +
                            " ".join(CFLAGS).encode()).hexdigest()[:16]
    library = cache_dir() / f"{name}-{digest}.so"
    if not library.exists():
        compiler = os.environ.get("CC", "gcc")
        if shutil.which(compiler) is None:
            raise NativeUnavailable(f"C compiler {compiler!r} not found")
        library.parent.mkdir(parents=True, exist_ok=True)
        partial = library.with_suffix(f".{os.getpid()}.tmp")
        includes = [f"-I{include}"] if include is not None else []
        result = subprocess.run([compiler, *CFLAGS, *includes, "-o", str(partial),
                                 *map(str, sources), "-lm"], capture_output=True, text=True)
        if result.returncode != 0:
            raise NativeUnavailable(f"compiling {name} failed:\n{result.stderr}")
        partial.replace(library)  # atomic: concurrent runs never load a half-written file
    return library


@lru_cache(maxsize=1)
def load() -> ctypes.CDLL:
    """Compile (once) and load the loop; raises NativeUnavailable if it cannot."""
    dll = ctypes.CDLL(str(compile_library("master_loop", [SOURCE])))
    dll.loop_run.restype = ctypes.c_long
    dll.loop_run.argtypes = [
        ctypes.POINTER(LoopFMU), ctypes.POINTER(ctypes.c_int), ctypes.c_int,
        ctypes.POINTER(LoopLink), ctypes.c_int, ctypes.c_void_p, ctypes.c_long,
        ctypes.POINTER(LoopProbe), ctypes.c_int, ctypes.c_long, ctypes.c_void_p,
        ctypes.c_double, ctypes.c_double, ctypes.c_long, ctypes.c_long,
        ctypes.POINTER(LoopFailure)]
    return dll
