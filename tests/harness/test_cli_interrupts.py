"""Ctrl-C at any moment of a command: outside the command itself too (while the
harness loads, while the command line is parsed), exit status 130 and one line, never
a KeyboardInterrupt traceback or death by the signal (harness/cli.py; a Ctrl-C while --out
is made or filled: test_outputs_commands.py)."""
from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest
from cli_runner import FMU_DIR, REPO

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


EMPS = REPO / "examples" / "emps" / "emps.toml"

# build_parser replaced by one that gets the signal: Ctrl-C while the line is parsed
WHILE_PARSING = textwrap.dedent("""
    import os, signal, sys, time
    import harness.cli
    original = harness.cli.build_parser
    def interrupted():
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(30)
        return original()
    harness.cli.build_parser = interrupted
    sys.exit(harness.cli.main(sys.argv[1:]))
""")


def test_ctrl_c_while_the_command_line_is_parsed_exits_130(tmp_path):
    script = tmp_path / "interrupted.py"
    script.write_text(WHILE_PARSING)
    result = subprocess.run([sys.executable, str(script), "--fmu-dir", str(FMU_DIR), "fmu",
                             "--model", str(EMPS), "--out", str(tmp_path / "out")],
                            cwd=REPO, capture_output=True, text=True, timeout=60)
    assert result.returncode == 130, result.stderr
    assert "Traceback" not in result.stderr and "interrupted" in result.stderr
    assert not (tmp_path / "out").exists()


def test_ctrl_c_while_the_harness_loads_exits_130(tmp_path):
    """`python -m harness`: the signal arrives while harness.cli is imported."""
    loader = tmp_path / "sitecustomize.py"  # runs before harness/__main__ imports the CLI
    loader.write_text(textwrap.dedent("""
        import builtins, os, signal
        real_import = builtins.__import__
        def importing(name, *args, **kwargs):
            if name == "numpy" and not os.environ.get("STO_TEST_SENT"):
                os.environ["STO_TEST_SENT"] = "1"
                os.kill(os.getpid(), signal.SIGINT)
            return real_import(name, *args, **kwargs)
        builtins.__import__ = importing
    """))
    import os
    env = {**os.environ, "PYTHONPATH": f"{tmp_path}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}
    env.pop("STO_TEST_SENT", None)
    result = subprocess.run([sys.executable, "-m", "harness", "--fmu-dir", str(FMU_DIR), "fmu",
                             "--model", str(EMPS), "--out", str(tmp_path / "out")],
                            cwd=REPO, capture_output=True, text=True, timeout=60, env=env)
    assert result.returncode == 130, result.stderr[-2000:]
    assert "Traceback" not in result.stderr and "interrupted" in result.stderr
