"""A .mat log that is no MATLAB file (text, cut, damaged, forged sizes that made scipy's
C reader die) is named with exit status 2 by every command that reads a log, never a
traceback or a crash (harness/mat_file.py)."""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from cli_runner import REPO, cli, refused

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


EMPS = REPO / "examples" / "emps" / "emps.toml"  # columns t, qm, vir


@pytest.fixture(scope="module")
def urdf() -> Path:
    from harness.robot.examples import example_urdf
    return Path(example_urdf("double_pendulum")[0])


# every command that reads a log: its arguments after the log (URDF: the robot's)
READERS = {
    "identify --robot": ["identify", "--robot", "URDF"],
    "identify --model": ["identify", "--model", str(EMPS)],
    "identify (t, y, u)": ["identify"],
    "validate --robot": ["validate", "--robot", "URDF"],
    "validate --model": ["validate", "--model", str(EMPS)],
}


def _mat(**kwargs) -> bytes:
    import scipy.io
    buffer = io.BytesIO()
    t = np.arange(100.0)
    scipy.io.savemat(buffer, {"t": t, "qm": np.sin(t), "vir": np.cos(t)}, **kwargs)
    return buffer.getvalue()


MALFORMED_MAT = {
    "33 bytes of text": lambda: b"hello, this is not a MATLAB file",  # IndexError in scipy
    "200 bytes of text": lambda: b"x" * 200,
    "cut in a variable": lambda: _mat()[:700],  # scipy's "could not read bytes" (OSError)
    "cut compressed": lambda: _mat(do_compression=True)[:300],
    "damaged compressed": lambda: (lambda b: b[:200] + bytes(64) + b[264:])(
        _mat(do_compression=True)),  # zlib.error
    "forged sizes": lambda: _forged_sizes(_mat()),  # scipy's C reader dies (SIGSEGV)
}


def _forged_sizes(content: bytes) -> bytes:
    """The last variable's array-flags size and data type overwritten: scipy's reader
    (its C part) reads out of bounds and the process dies by a segmentation fault."""
    forged = bytearray(content)
    start = forged.rindex(b"vir") - 44  # the variable's tag; its name is at byte 44
    forged[start + 13], forged[start + 49] = 194, 4
    return bytes(forged)


@pytest.mark.parametrize("content", list(MALFORMED_MAT))
@pytest.mark.parametrize("reader", ["identify --model", "identify --robot", "validate --model"])
def test_a_malformed_mat_file_is_named(tmp_path, urdf, reader, content):
    log = tmp_path / "log.mat"
    log.write_bytes(MALFORMED_MAT[content]())
    command, *rest = [str(urdf) if a == "URDF" else a for a in READERS[reader]]
    code, text = cli([command, str(log), *rest, "--out", str(tmp_path / "out")])
    assert code == 2, text
    refused(code, text, str(log), "not a readable MATLAB file")
