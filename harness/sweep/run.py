"""The sweep command and its run over a spec: the runs planned, executed on the Dask
cluster and tabled, the summary and figures written (the format: harness.sweep)."""
from __future__ import annotations

import argparse
import sys
import time
import uuid
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from ..json_files import strict_json
from ..outputs import OutputError, Outputs, shown, write_atomically
from ..paths import default_fmu_dir
from ..tempdirs import remove_stale
from ..values import argparse_type, integer, real
from .lock import OutputLocked, locked_output
from .plan import (
    DEFAULT_FMU_DIR,
    FMU_FILES,
    Run,
    SweepSpec,
    load_spec,
    parse_spec,
    run_key,
)
from .report import ProgressLine, headline_metrics, metric_unit, plot_summary, write_summary
from .schema import METHODS
from .simulation import SimulationPool, prepare, run_in_process, simulate
from .spec import CONNECT_TIMEOUT, MAX_WORKERS, ClusterError, SpecError
from .table import CSV_EXPORT, TABLE, ResultsTable, result_row

__all__ = ["ClusterError", "DEFAULT_FMU_DIR", "FMU_FILES", "METHODS", "OutputLocked",
           "ResultsTable", "Run", "SimulationPool", "SpecError", "SweepResult", "SweepSpec",
           "headline_metrics", "load_spec", "main", "metric_unit", "parse_spec", "plot_summary",
           "prepare", "register", "result_row", "run_in_process", "run_key", "run_sweep",
           "simulate"]


# ---- running a sweep -------------------------------------------------------------

@dataclass
class SweepResult:
    total: int            # runs in the spec
    resumed: int          # already in the table, skipped
    executed: int         # run now
    ok: int               # of the executed
    failed: int
    wall_time: float      # of the executed runs, submission to last result [s]
    workers: int
    table: Path
    plots: list[Path]
    failures: list[tuple[str, str]]  # (key, message) of the executed runs that failed
    failed_in_table: int = 0  # runs of the spec recorded failed, earlier ones included

    @property
    def runs_per_second(self) -> float:
        return self.executed / self.wall_time if self.wall_time > 0 else 0.0


def run_sweep(spec: SweepSpec, out: str | Path, fmu_dir: Path = DEFAULT_FMU_DIR, *,
              scheduler: str | None = None, client=None, n_workers: int | None = None,
              retry_failed: bool = False, plots: bool = True, progress: bool = True,
              stream=None, connect_timeout: float = CONNECT_TIMEOUT) -> SweepResult:
    """Runs the spec's missing runs on Dask and records them in DIR's results table
    (harness.sweep.table: DIR/results.parquet, DIR/results.csv).

    ``client``: an existing dask.distributed Client (else ``scheduler`` or a
    LocalCluster with ``n_workers`` workers is used and closed afterwards)."""
    with locked_output(Path(out)):  # one writer per folder: OutputLocked otherwise
        remove_stale()  # FMUs extracted by earlier, killed sweeps
        return _run_sweep(spec, Path(out), fmu_dir, scheduler=scheduler, client=client,
                          n_workers=n_workers, retry_failed=retry_failed, plots=plots,
                          progress=progress, stream=stream, connect_timeout=connect_timeout)


def _run_sweep(spec: SweepSpec, out: Path, fmu_dir: Path, *, scheduler, client, n_workers,
               retry_failed, plots, progress, stream, connect_timeout) -> SweepResult:
    stream = stream or sys.stderr
    table = ResultsTable(out)
    text, _ = strict_json(spec.source, default=str)
    write_atomically(out / "spec.json", lambda path: Path(path).write_text(text))
    runs = spec.runs()
    done = table.status()
    todo = [r for r in runs if r.key not in done or (retry_failed and done[r.key] != "ok")]
    resumed = len(runs) - len(todo)

    failures: list[tuple[str, str]] = []
    ok = failed = workers = 0
    wall = 0.0
    if todo:
        # Dask is imported only here: the command line starts without it.
        from .cluster import FMUWorkerPlugin, execute, fmu_payload, start_client

        own = client is None
        cluster = None
        if own:
            client, cluster = start_client(scheduler, n_workers, connect_timeout)
        plugin_name = None
        try:
            payload, digest = fmu_payload(Path(fmu_dir))
            # One plugin per sweep: concurrent sweeps on a shared cluster keep their own.
            plugin_name = f"sto-sweep-fmus-{digest}-{uuid.uuid4().hex[:8]}"
            client.register_plugin(FMUWorkerPlugin(payload, plugin_name), name=plugin_name)
            workers = len(client.scheduler_info().get("workers", {}))
            counter = (ProgressLine(f"sweep {spec.scenario}", len(todo), stream) if progress
                       else None)
            if progress and resumed:
                stream.write(f"sweep {spec.scenario}: {resumed} of {len(runs)} runs already in "
                             f"{table.path}, running {len(todo)}\n")
            start = time.perf_counter()
            ok, failed, failures = execute(client, plugin_name, spec, todo, table, counter)
            wall = time.perf_counter() - start
        finally:
            if plugin_name is not None and cluster is None:
                try:  # a shared cluster: free the workers' FMU instances
                    client.unregister_worker_plugin(plugin_name)
                except Exception:  # noqa: BLE001 - the workers may be gone
                    pass
            if own:
                client.close()
                if cluster is not None:
                    cluster.close()
    table.consolidate([r.key for r in runs])
    written: list[Path] = []
    rows = table.rows({r.key for r in runs})
    if plots and rows:
        written = plot_summary(spec, rows, out)
    write_summary(spec, rows, out, resumed=resumed, executed=len(todo), wall=wall,
                   workers=workers)
    return SweepResult(len(runs), resumed, len(todo), ok, failed, wall, workers, table.path,
                       written, failures, sum(r.get("status") != "ok" for r in rows))



# ---- command line ----------------------------------------------------------------

def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("spec", help="sweep specification (JSON, or TOML if it ends in .toml)")
    p.add_argument("--out", required=True, help="output folder (re-use it to resume)")
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                   help="a running Dask scheduler (default: a LocalCluster on this machine)")
    p.add_argument("--workers", default=None,
                   type=argparse_type(integer, "--workers", low=1, high=MAX_WORKERS),
                   help=f"LocalCluster worker processes, 1..{MAX_WORKERS} (default: one per core)")
    p.add_argument("--connect-timeout", default=CONNECT_TIMEOUT, metavar="SECONDS",
                   type=argparse_type(real, "--connect-timeout", low=0.0, low_open=True),
                   help="give up if the scheduler cannot be reached, or has no worker, within "
                        f"this time (default {CONNECT_TIMEOUT:g} s)")
    p.add_argument("--retry-failed", action="store_true",
                   help="run again the runs that the table records as failed")
    p.add_argument("--no-plots", action="store_true", help="write the table and summary only")
    p.add_argument("--dry-run", action="store_true",
                   help="list the runs (and which are already done) without running them")
    p.set_defaults(func=cmd_sweep)


def register(subparsers, parents: Sequence[argparse.ArgumentParser] = ()
             ) -> argparse.ArgumentParser:
    """Adds the ``sweep`` subcommand to the harness CLI's subparsers (``parents``: the
    options every command takes)."""
    p = subparsers.add_parser("sweep", help="parameter / noise sweeps on Dask",
                              description=_package_doc(), parents=list(parents),
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(p)
    return p


def cmd_sweep(args) -> int:
    fmu_dir = Path(getattr(args, "fmu_dir", None) or default_fmu_dir())
    try:
        spec = load_spec(args.spec, fmu_dir)
    except SpecError as error:
        print(f"harness sweep: {error}", file=sys.stderr)
        return 2
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        print(f"harness sweep: --out {out} exists and is not a folder", file=sys.stderr)
        return 2
    try:  # names the sweep writes: never an input (the spec), never out through a link
        guard = Outputs(out, "sweep", inputs=[args.spec, *sorted(fmu_dir.glob("*.fmu"))])
        for name in ("spec.json", "summary.json", TABLE, CSV_EXPORT):
            guard.check(name)
    except OutputError as error:
        print(error, file=sys.stderr)
        return 2
    runs = spec.runs()
    if args.dry_run:
        try:
            done = ResultsTable(out).status()
        except SpecError as error:
            print(f"harness sweep: {error}", file=sys.stderr)
            return 2
        swept = spec.swept
        print(f"{len(runs)} runs of {spec.scenario} ({spec.stop_time:g} s, {spec.method}); "
              f"swept: {', '.join(swept) or '(nothing)'}")
        for run in runs:
            state = done.get(run.key, "todo")
            values = ", ".join(f"{k} = {run.params[k]!r}" for k in swept if k in run.params)
            print(f"  {run.key}  {state:<6}  {values}")
        return 0
    try:
        result = run_sweep(spec, out, fmu_dir, scheduler=args.scheduler, n_workers=args.workers,
                           retry_failed=args.retry_failed, plots=not args.no_plots,
                           connect_timeout=args.connect_timeout,
                           progress=not getattr(args, "quiet", False))
    except (SpecError, ClusterError, OutputLocked) as error:
        print(f"harness sweep: {error}", file=sys.stderr)
        return 3 if isinstance(error, OutputLocked) else 2
    except OSError as error:
        print(f"harness sweep: {out}: {error.strerror or error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"\nharness sweep: interrupted; the finished runs are in {out}: run the "
              f"same command again to resume", file=sys.stderr)
        return 130
    print(f"sweep {spec.scenario}: {result.total} runs, {result.resumed} already done, "
          f"{result.executed} run now: {result.ok} ok, {result.failed} failed"
          + (f", {result.wall_time:.1f} s on {result.workers} "
             f"worker{'s' if result.workers != 1 else ''} "
             f"({result.runs_per_second:.2f} runs/s)" if result.executed else ""))
    print(f"wrote {shown(result.table)}, {CSV_EXPORT}, summary.json"
          + "".join(f", {shown(p.name)}" for p in result.plots))
    for key, message in result.failures[:10]:
        print(f"  failed {key}: {message}")
    if len(result.failures) > 10:
        print(f"  ... and {len(result.failures) - 10} more failed runs (see {TABLE})")
    if result.failed_in_table:  # exit status 1: not every run of the spec succeeded
        print(f"harness sweep: {result.failed_in_table} of {result.total} runs failed (see "
              f"{result.table}; --retry-failed runs them again)", file=sys.stderr)
        return 1
    return 0


def _package_doc() -> str:
    import harness.sweep
    return harness.sweep.__doc__ or ""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m harness.sweep", description=_package_doc(),
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(parser)
    parser.add_argument("--fmu-dir", default=str(DEFAULT_FMU_DIR),
                        help="folder with the FMUs (default: harness.paths."
                             "default_fmu_dir())")
    args = parser.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
