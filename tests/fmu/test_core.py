"""Unit tests of the plain-C algorithms (fmu/src/core), compiled without any FMI code."""
from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
CORE = REPO / "fmu" / "src" / "core"
SOURCE = Path(__file__).with_name("core") / "test_core.c"


@pytest.fixture(scope="module")
def binary(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("core") / "test_core"
    cmd = ["gcc", "-std=c11", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-O2",
           f"-I{CORE}", "-o", str(out), str(SOURCE), *map(str, sorted(CORE.glob("*.c"))), "-lm"]
    subprocess.run(cmd, check=True)
    return out


CASES = ["observer_exact_model", "observer_unknown_perturbation", "lsm_exact_data",
         "mff_tracking", "theorem_gains"]


def test_the_case_list_is_complete(binary):
    listed = subprocess.run([str(binary)], capture_output=True, text=True).stdout.split()
    assert listed == CASES


@pytest.mark.parametrize("case", CASES)
def test_core(binary, case):
    result = subprocess.run([str(binary), case], capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "FAIL" not in result.stdout
