"""Unit tests of the plain-C algorithms (fmu/src/core), compiled without any FMI code.

tests/fmu/core/test_core.c is compiled together with every fmu/src/core/*.c (with the
project's warning flags, into pytest's temporary directory) and run once per case; each
case prints one PASS/FAIL line per check with the figures it measured.
"""
from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
CORE = REPO / "fmu" / "src" / "core"
SOURCE = Path(__file__).with_name("core") / "test_core.c"
CFLAGS = ["-std=c11", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-O2"]

CASES = [
    "observer_exact_model",                      # finite-time convergence, xi = 0
    "observer_unknown_perturbation",             # F = 0, bounded unknown acceleration
    "filtered_injection_recovers_perturbation",  # zbar_eq = xi up to the filter lag (9)-(10)
    "lsm_exact_data",                            # (18)-(19) on z = Delta phi
    "lsm_standard_errors",                       # against the exact covariance, white and blue
    "mff_tracking",                              # (36)-(37), theta(t) = 1 + 0.5 sin 0.2t
    "mff_without_excitation",                    # wind-up: Gamma and the estimate, phi = 0
    "mff_pulses_and_resumption",                 # a rest with wrong pulses; less excitation
    "rri_mff_pulses_and_resumption",             # the same for the robots' regressor form
    "theorem_gains",                             # condition (6) by hand
    "coulomb_level_learned",                     # reversals: the Coulomb level learned
    "mean_sign_of_a_reversal",                   # the Coulomb regressor around a sample
    "statistics_job_equals_full_solve",          # sliced solve = rri_statistics at the snapshot
    "anchor_solve_spread",                       # the anchor = rri_solve at its snapshot
]


@pytest.fixture(scope="module")
def binary(tmp_path_factory) -> Path:
    compiler = shutil.which("gcc")
    if compiler is None:
        pytest.fail("gcc is needed to compile tests/fmu/core/test_core.c")
    out = tmp_path_factory.mktemp("core") / "test_core"
    cmd = [compiler, *CFLAGS, f"-I{CORE}", "-o", str(out), str(SOURCE),
           *map(str, sorted(CORE.glob("*.c"))), "-lm"]
    result = subprocess.run(cmd, capture_output=True, text=True)
    if result.returncode != 0:
        pytest.fail(f"compiling the core tests failed:\n{' '.join(cmd)}\n{result.stderr}")
    return out


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
