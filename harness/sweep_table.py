"""The results table of a sweep: one row per run, kept as runs complete.

In the output folder DIR:

- ``runs/<key>.parquet``: one file per finished run, written (to a temporary
  name, then renamed) the moment its result arrives, so a killed sweep loses
  no finished run and never leaves a half-written row;
- ``results.parquet``: the consolidated table, written at the end of a sweep
  from the previous table and the run files (a retried run's newer row
  replaces the older one), after which the run files it holds are removed;
- ``results.csv``: the same table as CSV (quoted header; read it with
  pandas.read_csv), rewritten with results.parquet.

Columns keep their types (numbers, Booleans, text; a value a run does not
have is null).  A re-run reads results.parquet and any run files left by an
interrupted sweep; a folder of an earlier version with only results.csv is
read from that file.  Read the table with ``pandas.read_parquet``.
"""
from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from .sweep_plan import Run, SweepSpec
from .sweep_spec import SpecError

TABLE = "results.parquet"
CSV_EXPORT = "results.csv"
RUNS = "runs"


def _write_atomically(path: Path, write) -> None:
    partial = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        write(str(partial))
        partial.replace(path)
    finally:
        partial.unlink(missing_ok=True)


def _table(rows: Sequence[Mapping[str, Any]]):
    """A pyarrow table of rows with any columns (the union, in first-seen order)."""
    import pyarrow as pa

    names = list(dict.fromkeys(name for row in rows for name in row))
    return pa.table({name: pa.array([row.get(name) for row in rows]) for name in names})


class ResultsTable:
    """The runs' rows of output folder ``out`` (see the module's description)."""

    def __init__(self, out: Path):
        self.out = Path(out)
        self.path = self.out / TABLE
        self.csv_path = self.out / CSV_EXPORT
        self.runs_dir = self.out / RUNS
        self._rows: dict[str, dict[str, Any]] = {}
        if self.path.exists():
            self._load(self.path)
        elif self.csv_path.exists():
            self._load(self.csv_path)
        for path in sorted(self.runs_dir.glob("*.parquet")) if self.runs_dir.is_dir() else []:
            try:
                self._load(path)
            except SpecError:
                path.unlink()  # not a finished run's row (renamed only once written)

    def _load(self, path: Path) -> None:
        import pyarrow as pa

        try:
            if path.suffix == ".csv":
                import pyarrow.csv as pacsv

                table = pacsv.read_csv(str(path))
            else:
                import pyarrow.parquet as pq

                table = pq.read_table(str(path))
        except (pa.ArrowException, OSError) as error:
            raise SpecError(f"{path} cannot be read ({error}); move it away to start afresh") \
                from None
        if table.num_columns == 0 or table.column_names[0] != "key":
            raise SpecError(f"{path} is not a sweep results table (no 'key' column)")
        for row in table.to_pylist():
            self._rows[row["key"]] = {k: v for k, v in row.items() if v is not None}

    def status(self) -> dict[str, str]:
        """key -> status of the runs in the table."""
        return {key: row.get("status", "") for key, row in self._rows.items()}

    def rows(self, keys: set[str]) -> list[dict[str, Any]]:
        """The rows of these runs (columns a run does not have left out)."""
        return [row for key, row in self._rows.items() if key in keys]

    def append(self, row: Mapping[str, Any]) -> None:
        """Records a run's row at once (a row of the same key, a retried run, is replaced)."""
        import pyarrow.parquet as pq

        row = {k: v for k, v in row.items() if v is not None}
        self.runs_dir.mkdir(parents=True, exist_ok=True)
        table = _table([row])
        _write_atomically(self.runs_dir / f"{row['key']}.parquet",
                          lambda path: pq.write_table(table, path))
        self._rows.pop(row["key"], None)
        self._rows[row["key"]] = row

    def consolidate(self, keys: Sequence[str]) -> None:
        """Writes results.parquet and results.csv (the given keys first, in that order,
        then the others), then removes the run files they now hold."""
        import pyarrow.csv as pacsv
        import pyarrow.parquet as pq

        if not self._rows:
            return
        position = {k: i for i, k in enumerate(keys)}
        ordered = sorted(self._rows.values(), key=lambda r: position.get(r["key"], len(position)))
        table = _table(ordered)
        _write_atomically(self.path, lambda path: pq.write_table(table, path))
        _write_atomically(self.csv_path, lambda path: pacsv.write_csv(table, path))
        if self.runs_dir.is_dir():
            for path in self.runs_dir.glob("*.parquet"):
                path.unlink()
            try:
                self.runs_dir.rmdir()
            except OSError:
                pass  # something else in it: left alone


def result_row(spec: SweepSpec, run: Run, result: Mapping[str, Any]) -> dict[str, Any]:
    return {"key": run.key, "status": result["status"], "message": result.get("message", ""),
            "wall_time": result.get("wall_time"), "worker": result.get("worker", ""),
            "scenario": spec.scenario, "stop_time": spec.stop_time,
            "transient": spec.transient, "method": spec.method,
            **run.params, **result.get("metrics", {})}
