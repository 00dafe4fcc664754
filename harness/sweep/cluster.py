"""Sweep runs on Dask: the cluster, the FMUs shipped to each worker once, and the
runs submitted and collected as they complete."""
from __future__ import annotations

import hashlib
import os
import shutil
import signal
import tempfile
import threading
from pathlib import Path
from typing import Any, cast

from distributed.diagnostics.plugin import WorkerPlugin

from ..tempdirs import owned_temp_dir, remove_stale
from .plan import FMU_FILES, Run, SweepSpec
from .report import ProgressLine
from .simulation import SimulationPool, prepare, simulate
from .spec import CONNECT_TIMEOUT, MAX_WORKERS, ClusterError
from .table import ResultsTable, result_row


def fmu_payload(fmu_dir: Path) -> tuple[dict[str, bytes], str]:
    payload = {}
    digest = hashlib.sha256()
    for filename in FMU_FILES.values():
        data = (fmu_dir / filename).read_bytes()
        payload[filename] = data
        digest.update(filename.encode() + b"\0" + data)
    return payload, digest.hexdigest()[:12]


class FMUWorkerPlugin(WorkerPlugin):
    """Writes the FMUs into the worker's local directory once and keeps the
    worker's pool of co-simulations (used by :func:`_worker_run`)."""

    def __init__(self, payload: dict[str, bytes], name: str):
        self.payload = payload
        self.name = name
        self.pool: SimulationPool | None = None
        self.directory: str | None = None

    def __getstate__(self):
        return {"payload": self.payload, "name": self.name}

    def __setstate__(self, state):
        self.payload, self.name = state["payload"], state["name"]
        self.pool, self.directory = None, None

    def setup(self, worker=None):
        remove_stale()  # FMUs extracted by killed processes on this machine
        base = getattr(worker, "local_directory", None) or tempfile.gettempdir()
        remove_stale(base)
        self.directory = str(owned_temp_dir("sweepfmus", base))
        for filename, data in self.payload.items():
            Path(self.directory, filename).write_bytes(data)
        self.pool = SimulationPool(Path(self.directory))

    def teardown(self, worker=None):
        if self.pool is not None:
            self.pool.close()
        if self.directory:
            shutil.rmtree(self.directory, ignore_errors=True)


def _worker_run(plugin_name: str, scenario, noise_std: float, seed: int) -> dict[str, Any]:
    from distributed import get_worker

    worker = get_worker()
    plugin = cast(FMUWorkerPlugin, worker.plugins[plugin_name])
    if plugin.pool is None:
        raise RuntimeError(f"worker {worker.name}: the FMU plugin was not set up")
    result = simulate(plugin.pool, scenario, noise_std, seed)
    result["worker"] = str(worker.name)
    return result

def start_client(scheduler: str | None, n_workers: int | None,
                 connect_timeout: float = CONNECT_TIMEOUT):
    """(client, cluster or None): the given scheduler, or a LocalCluster on loopback;
    ClusterError if the scheduler cannot be reached or no worker comes up within
    ``connect_timeout`` seconds (a sweep never waits forever for workers)."""
    from distributed import Client, LocalCluster

    if n_workers is not None and not 1 <= n_workers <= MAX_WORKERS:
        raise ClusterError(f"--workers {n_workers}: give 1 .. {MAX_WORKERS} worker processes")
    cluster = None
    try:
        if scheduler:
            client = Client(scheduler, timeout=f"{connect_timeout}s")
        else:
            # The workers start with SIGINT ignored (inherited): Ctrl-C stops the sweep
            # here, which cancels their runs, instead of printing a traceback per worker.
            # The scheduler's HTTP endpoint takes any free port (":0"), never warning
            # that 8787 is taken.
            previous = signal.signal(signal.SIGINT, signal.SIG_IGN) \
                if threading.current_thread() is threading.main_thread() else None
            try:
                cluster = LocalCluster(n_workers=n_workers or os.cpu_count() or 1,
                                       threads_per_worker=1, processes=True, host="127.0.0.1",
                                       dashboard_address=":0")
            finally:
                if previous is not None:
                    signal.signal(signal.SIGINT, previous)
            client = Client(cluster)
    except (OSError, ValueError, TypeError) as error:  # TimeoutError is an OSError
        where = f"the Dask scheduler at {scheduler}" if scheduler else "a local Dask cluster"
        raise ClusterError(f"cannot connect to {where} within {connect_timeout:g} s: "
                           f"{type(error).__name__}: {error}") from None
    try:
        client.wait_for_workers(1, timeout=connect_timeout)
    except (TimeoutError, OSError):
        client.close()
        if cluster is not None:
            cluster.close()
        where = f"the scheduler at {scheduler}" if scheduler else "the local cluster"
        raise ClusterError(f"{where} has no workers (none came up within "
                           f"{connect_timeout:g} s)") from None
    return client, cluster



def execute(client, plugin_name: str, spec: SweepSpec, todo: list[Run], table: ResultsTable,
             counter: ProgressLine | None) -> tuple[int, int, list[tuple[str, str]]]:
    from distributed import as_completed

    futures = {}
    for run in todo:
        scenario, noise_std, seed = prepare(spec, run)
        future = client.submit(_worker_run, plugin_name, scenario, noise_std, seed,
                               key=f"sto-run-{run.key}", pure=False, retries=0)
        futures[future] = run
    ok = failed = 0
    failures = []
    try:
        for future in as_completed(futures):
            run = futures[future]
            try:
                result = future.result()
            except Exception as error:  # noqa: BLE001 - e.g. KilledWorker: the FMU crashed
                result = {"status": "failed", "message": f"{type(error).__name__}: {error}",
                          "metrics": {}}
            future.release()
            table.append(result_row(spec, run, result))
            if result["status"] == "ok":
                ok += 1
            else:
                failed += 1
                failures.append((run.key, result.get("message", "")))
            if counter:
                counter.update(result["status"] != "ok")
    except KeyboardInterrupt:
        client.cancel(list(futures))
        raise
    return ok, failed, failures

