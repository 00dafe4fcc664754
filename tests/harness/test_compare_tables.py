"""harness.compare: the paper's settings against the defaults, as tables (a figure that
is never reached is inf in the CSV, null in the JSON)."""
from __future__ import annotations

import json
import math

from harness.compare import Row, markdown_table, write_tables


def test_the_tables_agree_and_an_unreached_figure_is_null_in_json(tmp_path):
    rows = [Row("pendulum", 0.0, "settling_time", 0.512, math.inf),
            Row("pendulum", 1e-4, "velocity_rms", 0.0123, 0.0045)]
    write_tables(rows, tmp_path)
    assert (tmp_path / "compare.csv").read_text().splitlines() == [
        "scenario,noise_std,metric,paper,improved",
        "pendulum,0.0,settling_time,0.512,inf",
        "pendulum,0.0001,velocity_rms,0.0123,0.0045"]
    assert json.loads((tmp_path / "compare.json").read_text())[0]["improved"] is None
    assert "| pendulum | 0.0001 | velocity_rms | 0.0123 | 0.0045 |" in markdown_table(rows)
