"""The results table of a sweep: one row per run, kept as runs complete."""
from __future__ import annotations

import csv
import io
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from .sweep_plan import Run, SweepSpec
from .sweep_spec import SpecError

TABLE = "results.csv"


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)  # round-trips exactly; inf, nan as such
    return str(value).replace("\r", " ").replace("\n", " | ")


class ResultsTable:
    """results.csv: one row per run, appended (and flushed) as runs complete.

    A new column (a parameter or metric not seen before) rewrites the file with
    the wider header; a half-written last line (an interrupted sweep) is dropped."""

    def __init__(self, path: Path):
        self.path = Path(path)
        self.header: list[str] = []
        self.rows: list[dict[str, str]] = []
        if self.path.exists():
            text = self.path.read_text()
            truncated = bool(text) and not text.endswith("\n")
            if truncated:
                text = text[:text.rfind("\n") + 1]
            reader = csv.DictReader(io.StringIO(text))
            self.header = list(reader.fieldnames or [])
            if self.header and self.header[0] != "key":
                raise SpecError(f"{self.path} is not a sweep results table (no 'key' column)")
            self.rows = [dict(r) for r in reader if r.get("key")]
            if truncated:
                self._rewrite()

    def status(self) -> dict[str, str]:
        """key -> status of the runs in the table (the last row of a key wins)."""
        return {r["key"]: r.get("status", "") for r in self.rows}

    def _rewrite(self, rows: list[dict[str, str]] | None = None) -> None:
        rows = self.rows if rows is None else rows
        partial = self.path.with_name(self.path.name + ".tmp")
        with partial.open("w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=self.header, restval="")
            writer.writeheader()
            writer.writerows(rows)
        partial.replace(self.path)

    def append(self, row: Mapping[str, Any]) -> None:
        """Adds a run's row; a row of the same key (a retried run) is replaced."""
        cells = {k: _cell(v) for k, v in row.items()}
        replaced = any(r["key"] == cells["key"] for r in self.rows)
        self.rows = [r for r in self.rows if r["key"] != cells["key"]] + [cells]
        new = [k for k in cells if k not in self.header]
        if new or replaced or not self.path.exists():
            self.header += new
            self._rewrite()
            return
        with self.path.open("a", newline="") as f:
            csv.DictWriter(f, fieldnames=self.header, restval="").writerow(cells)

    def reorder(self, keys: Sequence[str]) -> None:
        """Rewrite with the given keys first (in that order), the others after."""
        position = {k: i for i, k in enumerate(keys)}
        self.rows.sort(key=lambda r: position.get(r["key"], len(position)))
        if self.header:
            self._rewrite()


def result_row(spec: SweepSpec, run: Run, result: Mapping[str, Any]) -> dict[str, Any]:
    return {"key": run.key, "status": result["status"], "message": result.get("message", ""),
            "wall_time": result.get("wall_time"), "worker": result.get("worker", ""),
            "scenario": spec.scenario, "stop_time": spec.stop_time,
            "transient": spec.transient, "method": spec.method,
            **run.params, **result.get("metrics", {})}



def _number(text: str) -> Any:
    if text in ("True", "False"):
        return text == "True"
    for convert in (int, float):
        try:
            return convert(text)
        except ValueError:
            pass
    return text


def typed_rows(table: ResultsTable, keys: set[str]) -> list[dict[str, Any]]:
    """The table's rows of these runs, numbers parsed."""
    skip = {"key", "status", "message", "worker", "scenario", "method"}
    return [{k: (v if k in skip else _number(v)) for k, v in r.items() if v != ""}
            for r in table.rows if r["key"] in keys]

