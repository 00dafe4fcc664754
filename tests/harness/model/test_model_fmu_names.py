"""A model file's name with newlines or control characters, copied into the FMU it makes:
escaped, so the FMU stays readable (harness/model/fmu_export.py)."""
from __future__ import annotations

import zipfile

import numpy as np
import pytest
from cli_runner import cli
from model_text import model

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


@pytest.mark.parametrize("name", ["m\nsizes 7 7 7\n.toml", "m\x01\x1b[31m.toml", "m\u2028.toml"])
def test_a_model_file_name_with_newlines_or_controls_makes_a_readable_fmu(tmp_path, name):
    from lxml import etree

    from harness.model.program import evaluate_program
    path = model(tmp_path / name)
    code, text = cli(["fmu", "--model", str(path), "--out", str(tmp_path / "out")])
    assert code == 0, text
    fmu = next((tmp_path / "out").glob("*.fmu"))
    with zipfile.ZipFile(fmu) as archive:
        program = archive.read("resources/model.txt").decode()
        description = etree.fromstring(archive.read("modelDescription.xml"))
    assert program.splitlines()[2] == "sizes 1 1 2"  # the name stays on its comment line
    Y, r = evaluate_program(program, *(np.ones((3, 1)) for _ in range(4)))  # the C parser
    assert Y.shape == (3, 1, 2)
    assert "\n" not in description.get("modelName")
