"""identified.toml (harness/model/writer.py): a log's name with TOML in it stays in the
header's comment."""
from __future__ import annotations

import pytest
from model_text import model

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


def test_a_log_name_with_toml_in_it_stays_in_the_comment(tmp_path):
    """identified.toml's header names the files: a newline there would start TOML."""
    from harness.model import parse_model, read_model
    from harness.model.writer import model_toml
    path = model(tmp_path / "m.toml", extra='[units]\nx = "m"\nF = "N"\n')
    path.write_text(path.read_text().replace("M = { nominal = 1 }", 'M = { nominal = 1, unit = "kg" }')
                    .replace("Fv = { nominal = 1 }", 'Fv = { nominal = 1, unit = "kg/s" }'))
    source = read_model(path)
    text = model_toml(source, [2.0, 0.7], header=['m.toml identified from log\n[units]\n'
                                                  'x = "mm"\n\x7f.csv'])
    back = parse_model(text)
    assert back.units == source.units and back.nominal.tolist() == [2.0, 0.7]
    assert text.splitlines()[0].startswith("# m.toml identified from log\\n[units]")
