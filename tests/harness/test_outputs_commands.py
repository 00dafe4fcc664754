"""Outputs that would overwrite inputs, leave through links, fill a disk, meet a second
writer or a signal: every command refuses with exit status 2 (naming the file), or
writes all its files or none, and leaves no temporary behind.  A Ctrl-C while --out is made or
filled removes the folder the command created (harness.outputs).
"""
from __future__ import annotations

import errno
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from cli_runner import FMU_DIR, REPO, cli, refused

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


def recording(path: Path, n: int = 2000) -> Path:
    t = 1e-3 * np.arange(n)
    rows = np.column_stack([t, 0.1 * np.sin(2 * t) + 0.05 * np.sin(7 * t), np.cos(3 * t)])
    np.savetxt(path, rows, delimiter=",", header="t,y,u", comments="", fmt="%.17g")
    return path


def leftovers(folder: Path) -> list[Path]:
    """Temporaries of the output machinery left in ``folder``."""
    return [p for p in folder.rglob("*") if "sto-partial" in p.name or p.name.endswith(".tmp")]


@pytest.fixture(scope="module")
def urdf() -> Path:
    from harness.robot.examples import example_urdf
    return Path(example_urdf("double_pendulum")[0])


@pytest.fixture()
def finished(tmp_path) -> Path:
    """A folder holding the outputs of a finished identify run."""
    data = recording(tmp_path / "run.csv")
    out = tmp_path / "out"
    code, text = cli(["identify", str(data), "--out", str(out)])
    assert code == 0, text
    return out


def snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file() and not p.is_symlink()}


# ---- outputs that are inputs --------------------------------------------------------------

def test_identify_refuses_to_write_over_its_recording(tmp_path):
    data = recording(tmp_path / "estimates.csv")
    before = data.read_bytes()
    code, text = cli(["identify", str(data), "--out", str(tmp_path)])
    assert code == 2, text
    refused(code, text, "estimates.csv", "input")
    assert data.read_bytes() == before


def test_identify_robot_refuses_to_write_over_its_log(tmp_path, urdf):
    log = tmp_path / "velocities.csv"
    log.write_text("t,q1,q2,u1,u2\n" + "".join(f"{k * 1e-3},0,0,0,0\n" for k in range(50)))
    before = log.read_bytes()
    code, text = cli(["identify", str(log), "--robot", str(urdf), "--out", str(tmp_path)])
    assert code == 2, text
    refused(code, text, "velocities.csv", "input")
    assert log.read_bytes() == before


def test_identify_robot_refuses_to_write_over_its_urdf(tmp_path, urdf):
    copy = tmp_path / "identified.urdf"
    shutil.copy(urdf, copy)
    log = recording(tmp_path / "log.csv")
    code, text = cli(["identify", str(log), "--robot", str(copy), "--out", str(tmp_path)])
    assert code == 2, text
    refused(code, text, "identified.urdf", "input")
    assert copy.read_bytes() == urdf.read_bytes()


def test_robot_fmu_parameters_refuses_to_write_over_its_urdf(tmp_path, urdf):
    copy = tmp_path / "robot.urdf"
    shutil.copy(urdf, copy)
    code, text = cli(["robot-fmu-parameters", str(copy), "--out", str(copy)])
    assert code == 2, text
    refused(code, text, "robot.urdf", "input")
    assert copy.read_bytes() == urdf.read_bytes()


def test_fmu_refuses_to_write_over_its_model_file_saying_so_once(tmp_path):
    model = tmp_path / "emps.fmu"  # a model file named as the FMU the command writes
    model.write_text((REPO / "examples" / "emps" / "emps.toml").read_text())
    before = model.read_bytes()
    code, text = cli(["fmu", "--model", str(model), "--out", str(tmp_path)])
    assert code == 2, text
    refused(code, text, "writing it would overwrite the input")
    assert text.count("harness fmu:") == 1 and model.read_bytes() == before


def test_a_symbolic_link_out_of_the_folder_is_not_followed(tmp_path, finished):
    outside = tmp_path / "precious.csv"
    outside.write_text("keep me\n")
    (finished / "estimates.csv").unlink()
    (finished / "estimates.csv").symlink_to(outside)
    code, text = cli(["identify", str(tmp_path / "run.csv"), "--out", str(finished)])
    assert code == 2, text
    refused(code, text, "symbolic link")
    assert outside.read_text() == "keep me\n"


def test_an_output_name_that_is_a_folder_is_refused(tmp_path, urdf):
    folder = tmp_path / "robot.ssv"
    folder.mkdir()
    code, text = cli(["robot-fmu-parameters", str(urdf), "--out", str(folder)])
    assert code == 2, text
    refused(code, text, "is a folder")


def test_robot_fmu_parameters_creates_a_missing_folder(tmp_path, urdf):
    out = tmp_path / "new" / "deeper" / "robot.ssv"
    code, text = cli(["robot-fmu-parameters", str(urdf), "--out", str(out)])
    assert code == 0, text
    assert out.read_text().startswith("<?xml") and not leftovers(tmp_path)


@pytest.mark.parametrize("command", [["identify", "DATA"], ["reproduce", "--scenario", "6.2"]])
def test_out_naming_a_file_exits_2(tmp_path, command):
    data = recording(tmp_path / "run.csv")
    target = tmp_path / "file"
    target.write_text("x")
    code, text = cli([data.as_posix() if c == "DATA" else c for c in command]
                     + ["--out", str(target)])
    assert code == 2, text
    refused(code, text, "is not a folder")
    assert target.read_text() == "x"


# ---- full and read-only disks --------------------------------------------------------------

def test_a_full_disk_leaves_the_earlier_outputs_and_no_partial_file(tmp_path, finished,
                                                                     monkeypatch):
    from harness import tables

    before = snapshot(finished)
    original = tables.CsvStream.write
    calls = []

    def fill(self, columns):
        calls.append(1)
        original(self, columns)
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(tables.CsvStream, "write", fill)
    code, text = cli(["identify", str(tmp_path / "run.csv"), "--out", str(finished)])
    assert calls and code == 2, text
    refused(code, text, "No space left on device", "nothing was written")
    assert snapshot(finished) == before
    assert not leftovers(finished)


def test_a_read_only_folder_is_a_message(tmp_path, monkeypatch):
    from harness import outputs

    def read_only(kind, base=None):
        raise OSError(errno.EROFS, "Read-only file system", str(base))

    monkeypatch.setattr(outputs, "owned_temp_dir", read_only)
    out = tmp_path / "out"
    code, text = cli(["identify", str(recording(tmp_path / "run.csv")), "--out", str(out)])
    assert code == 2, text
    refused(code, text, "Read-only file system", str(out))
    assert not out.exists()


def test_a_failing_rename_at_the_end_is_a_message(tmp_path, finished, monkeypatch):
    from harness import outputs

    before = snapshot(finished)

    def no_rename(source, target):
        raise OSError(errno.ENOSPC, "No space left on device", str(target))

    monkeypatch.setattr(outputs.os, "replace", no_rename)
    code, text = cli(["identify", str(tmp_path / "run.csv"), "--out", str(finished)])
    assert code == 2, text
    refused(code, text, "No space left on device")
    assert snapshot(finished) == before and not leftovers(finished)


# ---- one writer per folder, signals ---------------------------------------------------------

HOLD = textwrap.dedent("""
    import sys, time
    from harness.outputs import Outputs
    with Outputs(sys.argv[1], "test"):
        print("held", flush=True)
        time.sleep(120)
""")


def test_a_second_writer_is_refused(tmp_path):
    data = recording(tmp_path / "run.csv")
    out = tmp_path / "out"
    holder = subprocess.Popen([sys.executable, "-c", HOLD, str(out)], cwd=REPO,
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        code, text = cli(["identify", str(data), "--out", str(out)])
        assert code == 2, text
        refused(code, text, "another harness command is writing to")
        assert not (out / "estimates.csv").exists()
    finally:
        holder.kill()
        holder.wait()
    code, text = cli(["identify", str(data), "--out", str(out)])  # released with the process
    assert code == 0, text


# identify_file replaced by one that writes half a table and then gets the signal
INTERRUPTED = textwrap.dedent("""
    import os, signal, sys, time
    import harness.identify
    def half(path, fmu, parameters, out_csv, **options):
        with open(out_csv, "w") as handle:
            handle.write("t,y,u\\n0,1,2\\n")
        os.kill(os.getpid(), getattr(signal, sys.argv[1]))
        time.sleep(30)
        raise AssertionError("the signal did not stop the run")
    harness.identify.identify_file = half
    from harness.cli import main
    sys.exit(main(sys.argv[2:]))
""")


@pytest.mark.parametrize("name, status", [("SIGINT", 130), ("SIGTERM", 143)])
def test_a_signal_leaves_the_earlier_outputs_whole(tmp_path, finished, name, status):
    before = snapshot(finished)
    script = tmp_path / "interrupted.py"
    script.write_text(INTERRUPTED)
    result = subprocess.run([sys.executable, str(script), name, "--fmu-dir", str(FMU_DIR),
                             "identify", str(tmp_path / "run.csv"), "--out", str(finished)],
                            cwd=REPO, capture_output=True, text=True, timeout=60)
    assert result.returncode == status, result.stderr
    assert "Traceback" not in result.stderr
    assert snapshot(finished) == before and not leftovers(finished)


def test_a_folder_left_by_a_killed_run_is_removed_by_the_next(tmp_path, finished):
    stale = finished / "sto-partial-999999999-abc"  # a process id that does not run
    stale.mkdir()
    (stale / "estimates.csv").write_text("t\n")
    code, text = cli(["identify", str(tmp_path / "run.csv"), "--out", str(finished)])
    assert code == 0, text
    assert not stale.exists()


def test_a_full_disk_under_robot_fmu_parameters_keeps_the_old_file(tmp_path, urdf,
                                                                    monkeypatch):
    from harness.robot import fmu

    target = tmp_path / "robot.ssv"
    target.write_text("the earlier parameters\n")

    def half(parameters, path, name="robot"):
        Path(path).write_text("<?xml")
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(fmu, "write_ssv", half)
    code, text = cli(["robot-fmu-parameters", str(urdf), "--out", str(target)])
    assert code == 2, text
    refused(code, text, "No space left on device", "nothing was written")
    assert target.read_text() == "the earlier parameters\n" and not leftovers(tmp_path)


def test_a_hard_link_to_the_input_is_refused(tmp_path):
    data = recording(tmp_path / "run.csv")
    out = tmp_path / "out"
    out.mkdir()
    (out / "estimates.csv").hardlink_to(data)
    before = data.read_bytes()
    code, text = cli(["identify", str(data), "--out", str(out)])
    assert code == 2, text
    refused(code, text, "input")
    assert data.read_bytes() == before


def test_a_loop_of_links_in_out_is_a_message(tmp_path):
    data = recording(tmp_path / "run.csv")
    out = tmp_path / "out"
    out.mkdir()
    (out / "estimates.csv").symlink_to(out / "estimates.csv")
    code, text = cli(["identify", str(data), "--out", str(out)])
    assert code == 2, text
    refused(code, text, "symbolic link")


SWEEP_HOLD = textwrap.dedent("""
    import sys, time
    from pathlib import Path
    from harness.sweep.lock import locked_output
    with locked_output(Path(sys.argv[1])):
        print("held", flush=True)
        time.sleep(120)
""")


def test_identify_into_a_folder_a_sweep_writes_is_refused(tmp_path):
    data = recording(tmp_path / "run.csv")
    out = tmp_path / "sweep"
    holder = subprocess.Popen([sys.executable, "-c", SWEEP_HOLD, str(out)], cwd=REPO,
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        code, text = cli(["identify", str(data), "--out", str(out)])
        assert code == 2, text
        refused(code, text, "another harness command is writing to")
    finally:
        holder.kill()
        holder.wait()


# A name holding ESC sequences, a bell, a carriage return and a newline: printed as they
# are, they would recolour or clear the terminal and rewrite the "wrote" line
HOSTILE_NAME = "out\x1b[2J\x1b]0;title\x07\r\nx"


@pytest.mark.parametrize("command", ["fmu", "robot-fmu-parameters", "identify"])
def test_the_wrote_line_shows_control_characters_escaped(tmp_path, urdf, command):
    out = tmp_path / HOSTILE_NAME
    args = {"fmu": ["fmu", "--model", str(REPO / "examples" / "emps" / "emps.toml"),
                    "--out", str(out)],
            "robot-fmu-parameters": ["robot-fmu-parameters", str(urdf), "--out",
                                     str(out) + ".ssv"],
            "identify": ["identify", str(recording(tmp_path / "run.csv")), "--out", str(out)],
            }[command]
    code, text = cli(args)
    assert code == 0, text
    assert not any(c in text for c in "\x1b\x07\r"), repr(text)
    wrote = [line for line in text.splitlines() if line.startswith("wrote ")]
    assert wrote and "out\\x1b[2J\\x1b]0;title\\x07\\r\\nx" in wrote[0], repr(text)


EMPS = REPO / "examples" / "emps" / "emps.toml"


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
