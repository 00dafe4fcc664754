"""bench.reports.realdata.compare: ratios of one method's scores between two grid runs."""
from __future__ import annotations

from bench.reports.realdata.compare import comparison, ratios


def _row(measurement: str, vel_rms: float, param_worst: float | None = None) -> dict:
    scores = {"vel_rms": vel_rms}
    if param_worst is not None:
        scores["param_worst"] = param_worst
    return {"dataset": "A", "plant": "accurate", "rate": 1000, "measurement": measurement,
            "model": "b-exact", "methods": {"fmu-default": {"scores": scores}}}


def test_ratios_pair_the_rows_of_both_runs():
    old = [_row("clean", 1.0, 0.1), _row("noise-1e-4", 2.0)]
    new = [_row("noise-1e-4", 3.0), _row("clean", 1.05, 0.1), _row("enc-16", 5.0)]
    pairs = ratios(old, new, "fmu-default", "vel_rms")
    assert sorted((a, b) for _, a, b in pairs) == [(1.0, 1.05), (2.0, 3.0)]  # enc-16: no old row


def test_comparison_lists_the_rows_that_moved():
    old = [_row("clean", 1.0, 0.1), _row("noise-1e-4", 2.0)]
    new = [_row("clean", 1.05, 0.1), _row("noise-1e-4", 3.0)]
    text = "\n".join(comparison(old, new, "fmu-default", 0.1))
    assert "| vel_rms | 2 | 1.275 | 1.05 | 1.5 |" in text
    assert "| param_worst | 1 | 1 | 1 | 1 |" in text
    assert "noise 1e-04" in text and "x1.5" in text
    assert "clean" not in text.split("Rows that moved")[1]  # 5 % is below the threshold
