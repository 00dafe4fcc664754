"""The results table of a sweep: one row per run, kept as runs complete.

In the output folder DIR:

- ``runs/<key>.parquet``: one file per finished run, written (to a temporary
  name, then renamed) the moment its result arrives, so a killed sweep loses
  no finished run and never leaves a half-written row;
- ``runs/MANIFEST``: the names of the run files the sweep wrote, one a line,
  each added before its file is renamed into place.  Only these files are
  read and only these are ever removed: anything else in runs/ is left alone,
  and a ``runs`` that is a symbolic link (which could point anywhere) is refused;
- ``results.parquet``: the consolidated table, written at the end of a sweep
  from the previous table and the run files (a retried run's newer row
  replaces the older one), after which the run files it holds are removed;
- ``results.csv``: the same table as CSV (quoted header; read it with
  pandas.read_csv), rewritten with results.parquet.

Columns keep their types (numbers, Booleans, text; a value a run does not
have is null).  A re-run reads results.parquet and the run files an
interrupted sweep listed in its manifest; a folder of an earlier version with
only results.csv is read from that file.  Reading (``ResultsTable(out)``, as
``--dry-run`` does) never changes the folder.  Read the table with
``pandas.read_parquet``.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ..outputs import write_atomically as _write_atomically
from .plan import Run, SweepSpec
from .spec import SpecError

TABLE = "results.parquet"
CSV_EXPORT = "results.csv"
RUNS = "runs"
MANIFEST = "MANIFEST"


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
        if self.runs_dir.is_symlink() or (self.runs_dir.exists() and not self.runs_dir.is_dir()):
            raise SpecError(f"{self.runs_dir} is a symbolic link or not a folder; the sweep "
                            f"writes its run files there: move it away")
        if self.path.exists():
            self._load(self.path)
        elif self.csv_path.exists():
            self._load(self.csv_path)
        for path in self._own_run_files():
            try:
                self._load(path)
            except SpecError:  # ours, unreadable (a full disk?): consolidate removes it
                continue

    def _own_run_files(self) -> list[Path]:
        """The run files the manifest lists that exist (plain files in runs/)."""
        try:
            names = (self.runs_dir / MANIFEST).read_text(encoding="utf-8").splitlines()
        except (FileNotFoundError, NotADirectoryError):
            return []
        except (OSError, UnicodeDecodeError) as error:
            raise SpecError(f"{self.runs_dir / MANIFEST} cannot be read ({error}); move "
                            f"{self.runs_dir} away to start afresh") from None
        paths = [self.runs_dir / name for name in dict.fromkeys(names)
                 if name.endswith(".parquet") and "/" not in name and not name.startswith(".")]
        return [p for p in paths if p.is_file() and not p.is_symlink()]

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
        name = f"{row['key']}.parquet"
        with (self.runs_dir / MANIFEST).open("a", encoding="utf-8") as manifest:
            manifest.write(name + "\n")  # before the file exists: every file of ours is listed
        _write_atomically(self.runs_dir / name, lambda path: pq.write_table(table, path))
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
            for path in self._own_run_files():  # only what this table wrote (the manifest)
                path.unlink()
            (self.runs_dir / MANIFEST).unlink(missing_ok=True)
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
