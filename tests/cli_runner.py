"""Running the harness command line as a user does, for the abuse tests.

``cli(args)`` runs ``python -m harness`` in-process and returns (exit status,
stdout + stderr); any exception other than SystemExit (a traceback for the
user) fails the test.  ``shell(args)`` runs it as a separate process with a
timeout, for what needs a real process (signals, concurrency).
"""
from __future__ import annotations

import contextlib
import io
import subprocess
import sys

from tools.abuse.abuse_fmi import REPO, fmu_dir

FMU_DIR = fmu_dir()  # $STO_FMU_DIR (the sanitized build under sanitize.sh) or build/fmus


def cli(args: list[str]) -> tuple[int, str]:
    from harness.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(["--fmu-dir", str(FMU_DIR), *args])
        except SystemExit as exit_:
            code = exit_.code
            if isinstance(code, str):  # SystemExit("message"): Python prints it, status 1
                err.write(code + "\n")
                code = 1
            code = 0 if code is None else code
    text = out.getvalue() + err.getvalue()
    assert "Traceback" not in text, text
    return code, text


def shell(args: list[str], timeout: float = 120.0, env: dict | None = None,
          module: str | None = None) -> subprocess.CompletedProcess:
    """``python -m harness ARGS`` (or ``python -m MODULE ARGS``) in a new process, from the
    repository root."""
    command = [sys.executable, "-m", module] if module else [sys.executable, "-m", "harness",
                                                       "--fmu-dir", str(FMU_DIR)]
    return subprocess.run(command + args, cwd=REPO, capture_output=True, text=True,
                          timeout=timeout, env=env)


def refused(code: int, text: str, *words: str) -> None:
    """A clear refusal: a nonzero status, each of ``words`` in the message, no traceback."""
    assert code != 0, f"exit status 0 for a bad input: {text[-500:]}"
    assert "Traceback" not in text, text
    for word in words:
        assert word in text, f"{word!r} not in {text[-800:]!r}"
