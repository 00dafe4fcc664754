"""The sweep removes only the run files it wrote itself (runs/MANIFEST): never a
user's file in runs/, never through a symbolic link, never on --dry-run."""
from __future__ import annotations

import json
from pathlib import Path

import pytest
from cli_runner import FMU_DIR, cli, refused

from harness import sweep

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code

BASE = {"scenario": "6.1-sine", "stop_time": 1.2, "points": [{"observer.tau": 0.02}]}


def spec_file(folder: Path) -> Path:
    path = folder / "spec.json"
    path.write_text(json.dumps(BASE))
    return path


def user_parquet(path: Path) -> Path:
    """A Parquet file of the user's that is not a results row."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    path.parent.mkdir(parents=True, exist_ok=True)
    pq.write_table(pa.table({"x": [1.0, 2.0]}), str(path))
    return path


def finished_run(out: Path) -> None:
    """A run file of an interrupted sweep that already holds the spec's run."""
    spec = sweep.parse_spec(BASE, FMU_DIR)
    sweep.ResultsTable(out).append(sweep.result_row(spec, spec.runs()[0],
                                                    {"status": "ok", "metrics": {}}))


def test_dry_run_deletes_nothing(tmp_path):
    out = tmp_path / "out"
    mine = user_parquet(out / "runs" / "notes.parquet")
    before = mine.read_bytes()
    code, text = cli(["sweep", str(spec_file(tmp_path)), "--out", str(out), "--dry-run"])
    assert code == 0, text
    assert mine.read_bytes() == before


def test_a_sweep_keeps_the_users_files_in_runs(tmp_path):
    out = tmp_path / "out"
    finished_run(out)
    mine = user_parquet(out / "runs" / "notes.parquet")
    code, text = cli(["sweep", str(spec_file(tmp_path)), "--out", str(out), "--no-plots"])
    assert code == 0, text
    assert mine.exists()
    assert sorted(p.name for p in (out / "runs").iterdir()) == ["notes.parquet"]
    assert len((out / "results.csv").read_text().splitlines()) == 2


@pytest.mark.parametrize("dry", [True, False])
def test_a_symbolic_link_runs_is_refused(tmp_path, dry):
    elsewhere = tmp_path / "elsewhere"
    mine = user_parquet(elsewhere / "precious.parquet")
    out = tmp_path / "out"
    out.mkdir()
    (out / "runs").symlink_to(elsewhere)
    code, text = cli(["sweep", str(spec_file(tmp_path)), "--out", str(out), "--no-plots"]
                     + (["--dry-run"] if dry else []))
    assert code == 2, text
    refused(code, text, "symbolic link")
    assert mine.exists()


def test_a_spec_inside_out_is_not_overwritten(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    spec = out / "spec.json"
    spec.write_text(json.dumps(BASE, indent=4) + "\n")
    before = spec.read_bytes()
    code, text = cli(["sweep", str(spec), "--out", str(out), "--no-plots"])
    assert code == 2, text
    refused(code, text, "spec.json", "input")
    assert spec.read_bytes() == before
