"""The case tables of the plain-C unit tests (fmu/src/core, built without any FMI code).

Each program tests/fmu/core/test_<name>.c is built by CMake with the core library, and
ctest runs each case of its case table (`./build.sh test`: ctest --preset default;
tools/abuse/sanitize.sh: ctest --preset sanitize); each case prints one PASS/FAIL line
per check with the figures it measured.  Here only the tables are checked: CMake reads
each from the source by its line pattern, so a case the program lists but the pattern
misses would never run, and an unknown case must be an error.
"""
from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SOURCES = sorted((Path(__file__).with_name("core")).glob("test_*.c"))
BUILD = Path(os.environ.get("STO_CMAKE_BUILD_DIR", REPO / "build" / "cmake"))
CASE_LINE = re.compile(r'^ *\{"([a-z_0-9]+)", [a-z_0-9]+\},', re.MULTILINE)


def binary(program: str) -> Path:
    path = BUILD / "bin" / program
    if not path.exists():
        pytest.fail(f"{path} is missing: run ./build.sh fmus (CMake's {program} target)")
    return path


@pytest.mark.parametrize("source", SOURCES, ids=lambda s: s.stem)
def test_the_case_list_is_complete(source):
    listed = subprocess.run([str(binary(source.stem))], capture_output=True, text=True,
                            check=True).stdout
    assert listed.split() == CASE_LINE.findall(source.read_text())


@pytest.mark.parametrize("source", SOURCES, ids=lambda s: s.stem)
def test_unknown_case_is_an_error(source):
    assert subprocess.run([str(binary(source.stem)), "no_such_case"],
                          capture_output=True).returncode == 2
