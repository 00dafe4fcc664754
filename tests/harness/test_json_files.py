"""harness.json_files: strict JSON; a figure that is not a finite number is written as
null and named, never as NaN or Infinity."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

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


@pytest.mark.cli
def test_every_json_written_is_strict_and_non_finite_figures_are_named(tmp_path, caplog):
    from harness.json_files import strict_json, write_json
    from harness.robot.validate import write_validation

    text, nulls = strict_json({"a": [1.0, float("nan")], "b": {"c": float("inf")}})
    assert json.loads(text, parse_constant=pytest.fail) == {"a": [1.0, None], "b": {"c": None}}
    assert nulls == ["a[1] (nan)", "b.c (inf)"]
    write_json(tmp_path / "x.json", {"pooled": float("-inf")})
    assert "pooled (-inf)" in caplog.text
    t = np.arange(20.0)
    write_validation(tmp_path, "r.urdf", "log.csv", 0.1, t, np.ones((20, 1)),
                     np.full((20, 1), 1e308), {"j1": float("inf")}, float("inf"))
    data = json.loads((tmp_path / "validation.json").read_text(), parse_constant=pytest.fail)
    assert data["relative_error"] == {"per_joint": {"j1": None}, "pooled": None}
    assert "relative_error.pooled (inf)" in caplog.text
