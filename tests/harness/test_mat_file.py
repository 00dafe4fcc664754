"""MATLAB files read in a child process: the numeric variables come back by name, the
others described, and a file that crashes scipy's reader is named, the caller alive."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.io

from harness.mat_file import MatFileError, load_mat


def test_numeric_variables_come_back_and_the_others_are_described(tmp_path):
    path = tmp_path / "log.mat"
    t = np.linspace(0.0, 1.0, 11)
    # "file" is np.savez's own argument name: a variable may still be called so
    scipy.io.savemat(path, {"t": t, "file": np.arange(3, dtype=np.int16), "note": "text",
                            "cell": np.array([[1.0], "a"], dtype=object)})
    variables = load_mat(path)
    assert sorted(variables) == ["file", "t"]
    np.testing.assert_array_equal(variables["t"].ravel(), t)
    assert variables["file"].dtype == np.int16
    assert sorted(variables.others) == ["cell", "note"]
    assert "type <U4" in variables.others["note"]


def test_a_file_that_crashes_the_reader_is_named(tmp_path):
    path = tmp_path / "forged.mat"
    scipy.io.savemat(path, {"u": np.ones(50)})
    forged = bytearray(path.read_bytes())
    start = forged.rindex(b"u") - 44  # the variable's tag (its one-letter name at byte 44)
    # its array-flags size and data type overwritten: scipy's C reader reads out of
    # bounds and its process dies by a segmentation fault
    forged[start + 13], forged[start + 49] = 194, 4
    path.write_bytes(forged)
    with pytest.raises(MatFileError, match=r"forged.mat: not a readable MATLAB file "
                                           r"\(scipy's reader crashed on it, SIGSEGV"):
        load_mat(path)


@pytest.mark.parametrize(("content", "said"), [
    (None, "no such file"),
    (b"t,q\n0,1\n", "not a readable MATLAB file"),
    (b"", "not a readable MATLAB file"),
])
def test_missing_and_foreign_files_are_named(tmp_path, content, said):
    path = tmp_path / "log.mat"
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(MatFileError, match=f"log.mat: {said}"):
        load_mat(path)
