"""The native master loop (native/master_loop.c) through ctypes: the loop runs in the
package's native library (`harness.native_library`), built with the package."""
from __future__ import annotations

import ctypes
from functools import lru_cache

from .native_library import NativeUnavailable, load_library

__all__ = ["NativeUnavailable", "load"]


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


@lru_cache(maxsize=1)
def load() -> ctypes.CDLL:
    """The loaded loop; raises NativeUnavailable if the native library is missing."""
    dll = load_library()
    dll.loop_run.restype = ctypes.c_long
    dll.loop_run.argtypes = [
        ctypes.POINTER(LoopFMU), ctypes.POINTER(ctypes.c_int), ctypes.c_int,
        ctypes.POINTER(LoopLink), ctypes.c_int, ctypes.c_void_p, ctypes.c_long,
        ctypes.POINTER(LoopProbe), ctypes.c_int, ctypes.c_long, ctypes.c_void_p,
        ctypes.c_double, ctypes.c_double, ctypes.c_long, ctypes.c_long,
        ctypes.POINTER(LoopFailure)]
    return dll
