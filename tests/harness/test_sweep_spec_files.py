"""Sweep spec files built to break a parser: deep nesting, other encodings, huge
integers, duplicate keys, huge files.  Each is refused with exit status 2 and a
message naming the file (and the line or entry), never a traceback."""
from __future__ import annotations

import json
from pathlib import Path

import pytest
from cli_runner import cli, refused

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


def dry_run(spec: Path, tmp_path: Path) -> tuple[int, str]:
    return cli(["sweep", str(spec), "--out", str(tmp_path / "out"), "--dry-run"])


@pytest.mark.parametrize("depth", [40, 5000, 100_000])
@pytest.mark.parametrize("suffix", [".json", ".toml"])
def test_deep_nesting_is_refused(tmp_path, depth, suffix):
    spec = tmp_path / f"spec{suffix}"
    nested = "[" * depth + "]" * depth
    spec.write_text(f'{{"scenario": "6.2", "x": {nested}}}' if suffix == ".json"
                    else f'scenario = "6.2"\nx = {nested}\n')
    code, text = dry_run(spec, tmp_path)
    assert code == 2, text
    refused(code, text, str(spec), "nested")


def test_deep_toml_keys_are_refused(tmp_path):
    spec = tmp_path / "spec.toml"
    spec.write_text('scenario = "6.2"\n' + ".".join(["k"] * 5000) + " = 1\n")
    code, text = dry_run(spec, tmp_path)
    assert code == 2, text
    refused(code, text, str(spec), "nested")


@pytest.mark.parametrize("suffix", [".json", ".toml"])
def test_a_latin_1_spec_names_the_file_and_line(tmp_path, suffix):
    spec = tmp_path / f"spec{suffix}"
    text = ('{\n"scenario": "6.2",\n"note": "Gr\u00fc\u00dfe"\n}' if suffix == ".json"
            else 'scenario = "6.2"\nnote = "Gr\u00fc\u00dfe"\n')
    spec.write_bytes(text.encode("latin-1"))
    code, out = dry_run(spec, tmp_path)
    assert code == 2, out
    refused(code, out, str(spec), "line 3" if suffix == ".json" else "line 2", "UTF-8")


@pytest.mark.parametrize("suffix", [".json", ".toml"])
def test_a_5000_digit_integer_names_its_entry(tmp_path, suffix):
    spec = tmp_path / f"spec{suffix}"
    digits = "9" * 5000
    spec.write_text(f'{{"scenario": "6.2", "fixed": {{"observer.scheme": {digits}}}}}'
                    if suffix == ".json" else
                    f'scenario = "6.2"\n[fixed]\n"observer.scheme" = {digits}\n')
    code, text = dry_run(spec, tmp_path)
    assert code == 2, text
    refused(code, text, str(spec), "observer.scheme", "digits")


def test_a_duplicate_key_is_refused(tmp_path):
    spec = tmp_path / "spec.json"
    spec.write_text('{"scenario": "6.2", "stop_time": 1, "stop_time": 2}')
    code, text = dry_run(spec, tmp_path)
    assert code == 2, text
    refused(code, text, str(spec), "'stop_time' is given twice")


def test_a_huge_file_is_refused_unread(tmp_path):
    spec = tmp_path / "spec.json"
    spec.write_text(json.dumps({"scenario": "6.2", "note": "x" * (17 << 20)}))
    code, text = dry_run(spec, tmp_path)
    assert code == 2, text
    refused(code, text, str(spec), "larger than")


def test_a_good_spec_reads_the_same(tmp_path):
    from harness.inputs import InputError, read_structured

    data = {"scenario": "6.2", "grid": {"observer.tau": [0.01, 0.02]}, "seeds": 3}
    (tmp_path / "a.json").write_text(json.dumps(data))
    (tmp_path / "b.toml").write_text('scenario = "6.2"\nseeds = 3\n[grid]\n'
                                     '"observer.tau" = [0.01, 0.02]\n')
    assert read_structured(tmp_path / "a.json") == data == read_structured(tmp_path / "b.toml")
    with pytest.raises(InputError, match="cannot read"):
        read_structured(tmp_path / "missing.json")
