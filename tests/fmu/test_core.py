"""Unit tests of the plain-C algorithms (fmu/src/core), built without any FMI code.

Each program tests/fmu/core/test_<name>.c is built by CMake with the core library
(ctest runs the same cases) and run here once per case of its case table; each case
prints one PASS/FAIL line per check with the figures it measured.
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
# (program, case) as each source's case table names them (CMake reads the same tables).
CASES = [(source.stem, case) for source in SOURCES for case in CASE_LINE.findall(source.read_text())]


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


@pytest.mark.parametrize(("program", "case"), CASES, ids=[f"{p}.{c}" for p, c in CASES])
def test_core(program, case):
    result = subprocess.run([str(binary(program)), case], capture_output=True, text=True,
                            timeout=60)
    report = f"{program} {case} (exit status {result.returncode}):\n{result.stdout}{result.stderr}"
    assert result.returncode == 0, report
    lines = result.stdout.splitlines()
    assert lines and all(line.startswith("PASS ") for line in lines), report
