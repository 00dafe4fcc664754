"""harness.json_files: strict JSON; a figure that is not a finite number is written as
null and named, never as NaN or Infinity."""
from __future__ import annotations

import json
import math

from harness.json_files import strict_json, write_json


def test_non_finite_figures_become_null_and_are_named():
    text, nulls = strict_json({"error": {"pooled": math.nan, "per": [1.0, math.inf]},
                               "ok": 2.5, "name": "x"})
    assert json.loads(text) == {"error": {"pooled": None, "per": [1.0, None]}, "ok": 2.5,
                                "name": "x"}
    assert nulls == ["error.pooled (nan)", "error.per[1] (inf)"]
    assert "NaN" not in text and "Infinity" not in text


def test_write_json_warns_per_null_unless_null_is_documented(tmp_path, caplog):
    write_json(tmp_path / "a.json", {"t": -math.inf})
    assert "a.json: t (-inf) is not a finite number, written as null" in caplog.text
    caplog.clear()
    write_json(tmp_path / "b.json", {"settling_time": math.nan}, warn=False)
    assert caplog.text == "" and json.loads((tmp_path / "b.json").read_text()) == {
        "settling_time": None}
