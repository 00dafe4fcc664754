"""The README's examples run as written: its Python blocks execute and every command line
it shows parses."""
from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from harness.cli import build_parser

REPO = Path(__file__).resolve().parents[2]
README = (REPO / "README.md").read_text()
PYTHON_BLOCKS = re.findall(r"```python\n(.*?)```", README, re.S)
COMMANDS = [line.split("#")[0].strip() for block in re.findall(r"```sh\n(.*?)```", README, re.S)
            for line in block.splitlines() if line.startswith("sto-harness ")]


@pytest.mark.parametrize("code", PYTHON_BLOCKS, ids=[f"block{i}" for i in
                                                    range(len(PYTHON_BLOCKS))])
def test_python_examples_run_as_written(code, observer_fmu):
    env = {**os.environ, "MPLBACKEND": "Agg"}
    result = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True,
                            text=True, env=env, timeout=600)
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.strip(), "the example prints its result"


def test_there_are_examples():
    assert len(PYTHON_BLOCKS) >= 2 and len(COMMANDS) >= 5


@pytest.mark.parametrize("command", COMMANDS)
def test_command_lines_parse(command):
    build_parser().parse_args(shlex.split(command)[1:])
