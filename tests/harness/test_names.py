"""harness.names: a name copied into a generated file stays one line of printable text."""
from __future__ import annotations

import pytest

from harness.names import plain


@pytest.mark.parametrize("name, written", [
    ("log.csv", "log.csv"),
    ("my log (2).csv", "my log (2).csv"),
    ("a\nb", "a\\nb"),
    ("tab\there", "tab\\there"),
    ("esc\x1b[31m", "esc\\x1b[31m"),
    ("line\u2028sep", "line\\u2028sep"),
    ("bytes\udcff", "bytes\\udcff"),
    ("ünïcödé", "ünïcödé"),
])
def test_each_unprintable_character_is_written_as_its_escape(name, written):
    assert plain(name) == written
    assert plain(name).isprintable()
