"""Clocks at the edges of float64: a step of 1e302 s, stamps from -1e308 to 1e308, a
step of 1e-12 s.  The robot and model-file readers share one clock: each is refused
with exit status 2 and a message naming the time column and the step or span, never
an OverflowError or a scipy traceback."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from cli_runner import REPO, cli, refused

pytestmark = pytest.mark.cli

EMPS = REPO / "examples" / "emps" / "emps.toml"  # columns t, qm, vir
N = 3000


def stamps(kind: str) -> np.ndarray:
    if kind == "huge step":
        return np.arange(N) * 1e302
    if kind == "tiny step":
        return np.arange(N) * 1e-12
    return np.concatenate([[-1e308], np.linspace(-1e307, 1e307, N - 2), [1e308]])


WORDS = {"huge step": ["1e+302 s", "step"], "tiny step": ["1e-12 s", "step"],
         "span": ["spans", "float64"]}


@pytest.fixture(scope="module")
def urdf() -> Path:
    from harness.robot.examples import example_urdf
    return Path(example_urdf("double_pendulum")[0])


def table(path: Path, t: np.ndarray, header: str, columns: int) -> Path:
    k = np.arange(N) * 1e-3
    values = [0.5 * np.sin((j + 1) * k) for j in range(columns)]
    np.savetxt(path, np.column_stack([t, *values]), delimiter=",", header=header,
               comments="", fmt="%.17g")
    return path


@pytest.mark.parametrize("kind", list(WORDS))
@pytest.mark.parametrize("command", ["identify", "validate"])
def test_a_robot_log_clock_at_float64_edges_is_refused(tmp_path, urdf, kind, command):
    log = table(tmp_path / "log.csv", stamps(kind), "t,q1,q2,u1,u2", 4)
    code, text = cli([command, str(log), "--robot", str(urdf), "--out", str(tmp_path / "o")])
    assert code == 2, text
    refused(code, text, str(log), *WORDS[kind])


@pytest.mark.parametrize("kind", list(WORDS))
@pytest.mark.parametrize("command", ["identify", "validate"])
def test_a_model_log_clock_at_float64_edges_is_refused(tmp_path, kind, command):
    log = table(tmp_path / "log.csv", stamps(kind), "t,qm,vir", 2)
    code, text = cli([command, str(log), "--model", str(EMPS), "--out", str(tmp_path / "o")])
    assert code == 2, text
    refused(code, text, str(log), "time column 't'", *WORDS[kind])
