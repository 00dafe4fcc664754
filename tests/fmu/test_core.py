"""Unit tests of the plain-C algorithms (fmu/src/core), built without any FMI code.

tests/fmu/core/test_core.c is built by CMake with the core library (the `test_core`
target; ctest runs the same cases) and run here once per case; each case prints one
PASS/FAIL line per check with the figures it measured.
"""
from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SOURCE = Path(__file__).with_name("core") / "test_core.c"
BUILD = Path(os.environ.get("STO_CMAKE_BUILD_DIR", REPO / "build" / "cmake"))
# The cases as test_core.c's case table names them (CMake reads the same table for ctest).
CASES = re.findall(r'^ *\{"([a-z_0-9]+)", [a-z_0-9]+\},', SOURCE.read_text(), re.MULTILINE)


@pytest.fixture(scope="module")
def binary() -> Path:
    path = BUILD / "bin" / "test_core"
    if not path.exists():
        pytest.fail(f"{path} is missing: run ./build.sh fmus (CMake's test_core target)")
    return path


def test_the_case_list_is_complete(binary):
    listed = subprocess.run([str(binary)], capture_output=True, text=True, check=True).stdout
    assert listed.split() == CASES


def test_unknown_case_is_an_error(binary):
    assert subprocess.run([str(binary), "no_such_case"], capture_output=True).returncode == 2


@pytest.mark.parametrize("case", CASES)
def test_core(binary, case):
    result = subprocess.run([str(binary), case], capture_output=True, text=True, timeout=60)
    report = f"test_core {case} (exit status {result.returncode}):\n{result.stdout}{result.stderr}"
    assert result.returncode == 0, report
    lines = result.stdout.splitlines()
    assert lines and all(line.startswith("PASS ") for line in lines), report
