"""A model file's log whose force column is 1e200 or 1e307 times too large: estimates that
are not finite are an error, not a file; a column so large that the equations overflow
is named (exit status 2)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from cli_runner import cli, refused
from model_text import model

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


def mass_log(path: Path, scale: float = 1.0, seconds: float = 8.0) -> Path:
    """x of M x'' + Fv x' = F (M = 2, Fv = 0.7) driven by two sines; F times ``scale``."""
    t = np.arange(0.0, seconds, 1e-3)
    force = np.sin(2 * np.pi * 0.5 * t) + 0.5 * np.sin(2 * np.pi * 1.3 * t)
    x, v = np.zeros_like(t), 0.0
    for k in range(1, len(t)):
        v += (force[k - 1] - 0.7 * v) / 2.0 * 1e-3
        x[k] = x[k - 1] + v * 1e-3
    np.savetxt(path, np.column_stack([t, x, force * scale]), delimiter=",", header="t,x,F",
               comments="", fmt="%.17g")
    return path


def test_estimates_that_are_not_finite_are_an_error_not_a_file(tmp_path):
    """A force column 1e200 times too large: the least squares' errors overflow."""
    path = model(tmp_path / "m.toml")
    out = tmp_path / "out"
    code, text = cli(["identify", str(mass_log(tmp_path / "log.csv", 1e200)), "--model",
                      str(path), "--out", str(out), "--refine", "none"])
    assert code == 2, text
    refused(code, text, "log.csv", "not a finite number", "scaling")
    assert not (out / "parameters.csv").exists()


def test_a_column_so_large_that_the_equations_overflow_is_named(tmp_path):
    """A force column 1e307 times too large: the filtered log overflows; the refusal names
    the column and its size, and no numpy warning reaches the user."""
    path = model(tmp_path / "m.toml")
    code, text = cli(["identify", str(mass_log(tmp_path / "log.csv", 1e307)), "--model",
                      str(path), "--out", str(tmp_path / "out"), "--refine", "none"])
    refused(code, text, "log.csv", "overflow", "'F'", "unit or scale")
    assert "RuntimeWarning" not in text
