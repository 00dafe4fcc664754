"""harness.inputs: input files read within bounds (size, nesting, integer digits), as
UTF-8, from regular files only; each problem named with the file."""
from __future__ import annotations

import os

import pytest

from harness.inputs import (
    MAX_DEPTH,
    InputError,
    check_toml_nesting,
    read_structured,
    read_text,
)


def test_text_is_read_as_utf8_within_its_limit(tmp_path):
    path = tmp_path / "a.toml"
    path.write_bytes("\ufeffname = \"μ\"\n".encode())
    assert read_text(path) == 'name = "μ"\n'
    with pytest.raises(InputError, match="larger than 5 bytes"):
        read_text(path, limit=5)
    path.write_bytes(b"ok\n\xff\n")
    with pytest.raises(InputError, match=r"a.toml line 2: byte 0xff is not UTF-8"):
        read_text(path)


def test_folders_pipes_and_endless_devices_are_refused(tmp_path):
    with pytest.raises(InputError, match="the model file (is a folder|.Is a directory)"):
        read_text(tmp_path, "model file")
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    with pytest.raises(InputError, match="is a pipe or a socket"):
        read_text(fifo)  # opening it would wait for a writer
    with pytest.raises(InputError, match="not a regular file: a device or a pipe"):
        read_text("/dev/zero", limit=1000)


def test_toml_nesting_is_measured_on_the_text():
    assert check_toml_nesting("a = [[1], {b = 2}]  # [[[[") is None
    deep = "a = " + "[" * (MAX_DEPTH + 1) + "]" * (MAX_DEPTH + 1)
    assert "nested more than" in check_toml_nesting(deep)
    dotted = "x" + ".x" * (MAX_DEPTH + 1) + " = 1"
    assert "dotted key nested more than" in check_toml_nesting(dotted)
    assert check_toml_nesting('s = "[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[["') is None


def test_structured_files_refuse_twice_given_keys_and_huge_integers(tmp_path):
    json_file = tmp_path / "spec.json"
    json_file.write_text('{"seeds": 1, "seeds": 2}')
    with pytest.raises(InputError, match="the key 'seeds' is given twice"):
        read_structured(json_file)
    json_file.write_text('{"seeds": ' + "9" * 1200 + "}")
    with pytest.raises(InputError, match="seeds: an integer of 1200 digits"):
        read_structured(json_file)
    toml_file = tmp_path / "spec.toml"
    toml_file.write_text("seeds = 3\n[grid]\nnoise_std = [1e-5]\n")
    assert read_structured(toml_file) == {"seeds": 3, "grid": {"noise_std": [1e-5]}}
