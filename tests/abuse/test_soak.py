"""tools/abuse/soak.py (the closed loop's soak run) as a user types it: bad options are
refused with a message, never a traceback; short chunks run and check something.
"""
from __future__ import annotations

import math

import pytest
from cli_runner import refused, shell

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


SOAK = "tools.abuse.soak"


@pytest.mark.parametrize("args, words", [
    (["--chunk", "0"], "--chunk = 0.0 must be > 0"), (["--chunk", "-1"], "must be > 0"),
    (["--chunk", "0.00015"], "whole number of communication steps"),
    (["--chunk", "nan"], "not finite"), (["--seconds", "0"], "--seconds = 0.0 must be > 0"),
    (["--seconds", "-5"], "must be > 0"), (["--seconds", "inf"], "not finite"),
    (["--noise", "-1"], "must be >= 0"), (["--rss-slack", "nan"], "not finite"),
    (["--scenario", "7.1"], "invalid choice"),
])
def test_soak_bad_option(args, words):
    result = shell(args, module=SOAK, timeout=60)
    refused(result.returncode, result.stdout + result.stderr, words)


def test_soak_short_chunks_run_and_check_something(tmp_path):
    """--chunk 0.001 (10 steps) used to fail with a ValueError; a tiny --seconds runs a chunk."""
    summary = tmp_path / "soak.json"
    result = shell(["--chunk", "0.001", "--seconds", "0.0005", "--out", str(summary)],
                   module=SOAK, timeout=120)
    assert result.returncode == 0, result.stdout + result.stderr
    import json
    data = json.loads(summary.read_text())
    assert data["macro_steps"] >= 10 and len(data["chunks"]) == 1
    assert math.isfinite(data["gamma_trace_end"])
