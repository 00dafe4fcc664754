"""Ctrl-C at any moment of a command: outside the command itself too (while the
harness loads, while the command line is parsed), exit status 130 and one line, never
a KeyboardInterrupt traceback or death by the signal."""
from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest
from cli_runner import FMU_DIR, REPO

pytestmark = pytest.mark.cli

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


# Outputs' step replaced by one that gets the signal: Ctrl-C at that moment of --out's
# creation (after the lock, after the handler is set: a folder holding only
# .sto-harness.lock and the staging folder was left) or at the block's end (before the
# renames: the staging folder went and the created folder stayed, holding only the lock)
AT_OUTPUTS_STEP = textwrap.dedent("""
    import os, signal, sys
    import harness.cli
    from harness.outputs import Outputs
    method, when = sys.argv.pop(1), sys.argv.pop(1)
    original = getattr(Outputs, method)
    def interrupted(self, *args, **kwargs):
        if when == "before":
            os.kill(os.getpid(), signal.SIGINT)
        result = original(self, *args, **kwargs)
        if when == "after":
            os.kill(os.getpid(), signal.SIGINT)
        return result
    setattr(Outputs, method, interrupted)
    sys.exit(harness.cli.main(sys.argv[1:]))
""")


@pytest.mark.parametrize("method, when", [("_acquire", "after"), ("_catch_signals", "after"),
                                          ("_commit", "before")])
def test_ctrl_c_while_the_out_folder_is_made_or_filled_removes_it(tmp_path, method, when):
    """A folder the command created is removed when it is interrupted, whenever the
    signal comes (harness.outputs): never left holding only the lock."""
    script = tmp_path / "interrupted.py"
    script.write_text(AT_OUTPUTS_STEP)
    out = tmp_path / "out"
    result = subprocess.run([sys.executable, str(script), method, when, "--fmu-dir",
                             str(FMU_DIR), "fmu", "--model", str(EMPS), "--out", str(out)],
                            cwd=REPO, capture_output=True, text=True, timeout=60)
    assert result.returncode == 130, result.stderr
    assert "Traceback" not in result.stderr and "interrupted" in result.stderr
    assert not out.exists(), sorted(p.name for p in out.iterdir())
