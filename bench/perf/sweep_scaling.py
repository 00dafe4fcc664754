"""Sweep throughput on Dask: runs per second with 1, 2, ... worker processes.

    .venv/bin/python -m bench.perf.sweep_scaling [--runs 16] [--stop-time 2] [--workers 1,2]
                                            [--repeats 3]

Each measurement runs ``--runs`` closed-loop 6.1-sine runs of ``--stop-time``
seconds (noise std 1e-5 rad, one noise seed per run, so every run is distinct)
on a LocalCluster with N worker processes of one thread each, and reports the
median over ``--repeats`` of:

- sweep: harness.sweep.run_sweep into a fresh folder on an already started
  cluster: what a user waits for, minus the cluster start (shipping the FMUs
  to the workers, their first instantiation, writing the table; no plots);
- warm: the same runs on workers that already hold their FMU instances
  (the rate a long sweep settles at).

A serial in-process baseline (no Dask, one reused set of instances) gives
the cost of one run and so Dask's overhead.  The speed-up is warm(N)/warm(1).
Results vary with the machine's load: quote medians and the speed-up.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

from harness import sweep
from harness.sweep import cluster as sweep_dask

REPO = Path(__file__).resolve().parents[2]

FMU_DIR = REPO / "build" / "fmus"


def make_spec(runs: int, stop_time: float, offset: int = 0) -> sweep.SweepSpec:
    return sweep.parse_spec({"scenario": "6.1-sine", "stop_time": stop_time,
                             "grid": {"noise_std": [1e-5]},
                             "seeds": list(range(offset, offset + runs))}, FMU_DIR)


def serial(spec: sweep.SweepSpec) -> float:
    runs = spec.runs()
    pool = sweep.SimulationPool(FMU_DIR)
    try:
        scenario, noise, seed = sweep.prepare(spec, runs[0])
        sweep.simulate(pool, scenario, noise, seed)  # instantiate, compile the native loop
        start = time.perf_counter()
        for run in runs:
            result = sweep.simulate(pool, *sweep.prepare(spec, run))
            assert result["status"] == "ok", result["message"]
        return len(runs) / (time.perf_counter() - start)
    finally:
        pool.close()


def warm(client, spec: sweep.SweepSpec, workers: int) -> float:
    """Runs per second on workers that already hold their instances."""
    payload, digest = sweep_dask.fmu_payload(FMU_DIR)
    name = f"bench-fmus-{digest}"
    client.register_plugin(sweep.FMUWorkerPlugin(payload, name), name=name)
    try:
        with tempfile.TemporaryDirectory() as folder:
            warmup = make_spec(4 * workers, spec.stop_time, offset=10_000)
            table = sweep.ResultsTable(Path(folder) / "warmup")
            sweep_dask.execute(client, name, warmup, warmup.runs(), table, None)
            table = sweep.ResultsTable(Path(folder) / "results")
            start = time.perf_counter()
            ok, failed, _ = sweep_dask.execute(client, name, spec, spec.runs(), table, None)
            rate = len(spec.runs()) / (time.perf_counter() - start)
            assert failed == 0
            return rate
    finally:
        client.unregister_worker_plugin(name)


def end_to_end(client, spec: sweep.SweepSpec) -> float:
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        result = sweep.run_sweep(spec, Path(folder), FMU_DIR, client=client, plots=False,
                                 progress=False)
        elapsed = time.perf_counter() - start
        assert result.failed == 0
        return result.executed / elapsed


def main() -> int:
    from distributed import Client, LocalCluster

    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=16)
    parser.add_argument("--stop-time", type=float, default=2.0)
    parser.add_argument("--workers", default="1,2", help="comma-separated worker counts")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    spec = make_spec(args.runs, args.stop_time)
    print(f"{args.runs} runs of 6.1-sine, {args.stop_time:g} s each (noise 1e-5), "
          f"median of {args.repeats}")
    base = statistics.median(serial(spec) for _ in range(args.repeats))
    print(f"serial, in process (no Dask): {base:6.2f} runs/s ({1e3 / base:.1f} ms per run)")
    rates = {}
    for n in (int(w) for w in args.workers.split(",")):
        start = time.perf_counter()
        with LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                          dashboard_address=None) as cluster, Client(cluster) as client:
            client.wait_for_workers(n)
            started = time.perf_counter() - start
            sweep_rate = statistics.median(end_to_end(client, spec) for _ in range(args.repeats))
            warm_rate = statistics.median(warm(client, spec, n) for _ in range(args.repeats))
        rates[n] = warm_rate
        print(f"{n} worker{'s' if n > 1 else ' '}: sweep {sweep_rate:6.2f} runs/s, warm "
              f"{warm_rate:6.2f} runs/s (cluster start {started:.1f} s)")
    if 1 in rates:
        for n, rate in rates.items():
            if n != 1:
                print(f"speed-up {n} workers / 1 worker (warm): {rate / rates[1]:.2f} "
                      f"(efficiency {100 * rate / rates[1] / n:.0f} %)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
