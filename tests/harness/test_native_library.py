"""harness.native_library and harness.native_loop: the package's native library loaded
once, its absence named with what to run; the master loop's entry point typed."""
from __future__ import annotations

import ctypes

import pytest

from harness import native_library, native_loop


def test_the_library_loads_once_with_the_loop_typed():
    assert native_library.load_library() is native_library.load_library()
    loop = native_loop.load()
    assert loop.loop_run.restype is ctypes.c_long and len(loop.loop_run.argtypes) == 16


def test_a_missing_library_says_how_to_build_it(monkeypatch, tmp_path):
    monkeypatch.setattr(native_library, "library_path", lambda: tmp_path / "libsto_native.so")
    native_library.load_library.cache_clear()
    try:
        with pytest.raises(native_library.NativeUnavailable,
                           match=r"is not built: in a checkout run \./build\.sh fmus"):
            native_library.load_library()
    finally:
        native_library.load_library.cache_clear()  # the real library for the other tests
