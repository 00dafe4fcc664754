"""Two runs of the same grid side by side: how one method's scores moved.

    .venv/bin/python -m bench.reports.realdata.compare OLD/results.json NEW/results.json
                                                      [--method fmu-default]

For each summary metric: the median, the smallest and the largest ratio new / old over
the rows both runs scored, and the rows that moved by more than --threshold (default
10 %).  Used to check that a change of the observer keeps the grids' results (a
tuning, a cheaper rule) and to measure what a rule buys (a run without it).
"""
from __future__ import annotations

import argparse
import json
import math
import statistics
from pathlib import Path

from .report import SUMMARY_METRICS, Row, short_label, value


def _key(row: Row) -> tuple[object, ...]:
    return (row["dataset"], row["plant"], row["rate"], row["measurement"], row["model"])


def ratios(old: list[Row], new: list[Row], method: str, metric: str
           ) -> list[tuple[str, float, float]]:
    """(row label, old score, new score) for the rows both runs scored with `method`."""
    before = {_key(r): r for r in old}
    out = []
    for row in new:
        prior = before.get(_key(row))
        if prior is None or metric not in row["methods"][method]["scores"]:
            continue
        a, b = value(prior, method, metric), value(row, method, metric)
        if math.isfinite(a) and math.isfinite(b) and a > 0:
            out.append((short_label(row), a, b))
    return out


def comparison(old: list[Row], new: list[Row], method: str, threshold: float) -> list[str]:
    """The markdown lines of the comparison."""
    lines = [f"{method}: new / old per row", "",
             "| metric | rows | median | min | max |", "|---|---|---|---|---|"]
    moved = []
    for metric in SUMMARY_METRICS:
        pairs = ratios(old, new, method, metric)
        if not pairs:
            continue
        r = [b / a for _, a, b in pairs]
        lines.append(f"| {metric} | {len(r)} | {statistics.median(r):.4g} | {min(r):.4g} | "
                     f"{max(r):.4g} |")
        moved += [f"* {label}: {metric} {a:.4g} -> {b:.4g} (x{b / a:.3g})"
                  for label, a, b in pairs if abs(b / a - 1.0) > threshold]
    lines += ["", f"Rows that moved by more than {threshold:.0%}:", ""]
    return lines + (moved or ["* none"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("old", type=Path, help="results.json of the reference run")
    parser.add_argument("new", type=Path, help="results.json of the run to compare")
    parser.add_argument("--method", default="fmu-default")
    parser.add_argument("--threshold", type=float, default=0.1,
                        help="list the rows whose ratio is off 1 by more than this")
    args = parser.parse_args()
    old, new = (json.loads(p.read_text())["rows"] for p in (args.old, args.new))
    print("\n".join(comparison(old, new, args.method, args.threshold)))


if __name__ == "__main__":
    main()
