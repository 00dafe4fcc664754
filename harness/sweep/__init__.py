"""Parameter sweeps of the closed-loop scenarios on Dask.

    python -m harness sweep SPEC --out DIR [--scheduler tcp://HOST:PORT] [--workers N]
                                           [--retry-failed] [--no-plots] [--dry-run]

Runs every combination that SPEC describes, each a closed-loop scenario run
(observer + pendulum + twisting controller) scored by harness.metrics.score,
on a Dask cluster: a LocalCluster on this machine by default (one worker
process per core, one thread each), or the running scheduler given by
``--scheduler`` (its workers need this package and fmpy installed; the FMUs
are shipped to them, no shared file system is needed).

SPEC is a JSON file (or TOML, if its name ends in .toml), for example:

    {
      "scenario": "6.1-sine",
      "stop_time": 2.0,
      "transient": 1.0,
      "method": "paper",
      "fixed": {"observer.tau": 0.01},
      "grid": {"observer.alpha1[1]": [2.2, 4.4], "noise_std": [0, 1e-5, 1e-4]},
      "random": {
        "method": "lhs", "n": 20, "seed": 1,
        "ranges": {
          "observer.alpha2[1]": [10, 40],
          "observer.tau": {"low": 1e-3, "high": 1e-1, "scale": "log"}
        }
      },
      "points": [{"observer.h": 2e-4}],
      "seeds": [0, 1, 2]
    }

Its keys (only "scenario" is required):
  scenario   a name of harness.scenarios.SCENARIOS
  stop_time  override the scenario's length [s]
  transient  override the metrics' transient [s]
  method     "paper" (the scenario as is) or "improved" (scenarios.improved_overrides)
  fixed      the same value in every run
  grid       the cartesian product of these lists
  random     n samples crossed with the grid: "lhs" (Latin hypercube) or "uniform",
             the sampling seed, and per parameter [low, high] (uniform) or
             {"low", "high", "scale": "log"}
  points     extra runs (each crossed with the seeds)
  seeds      noise seeds (or an int n: seeds 0..n-1); default [0]

A parameter is "fmu.variable" with fmu one of plant, controller, observer and
a variable of that FMU, e.g. "observer.alpha1[1]", "observer.scheme",
"plant.Vs", "controller.k1"; values are converted to the variable's type
(Integer parameters sampled from a range are rounded).  Two pseudo-parameters:
"noise_std" (std of the white noise on the measured theta [rad], default 0)
and "seed" (the noise seed; give either "seeds" or a "seed" entry).  Values
override, in this order, the scenario's, the method's, "fixed", then the
swept ones.  The runs are (grid x random samples) + points, each x seeds;
a noise-free run (noise_std = 0) does not depend on the seed and runs once.

Outputs in DIR:
  results.parquet  one row per run: key, status (ok/failed), message, wall_time [s],
                worker, scenario, stop_time, method, every run parameter, every metric
                (pandas.read_parquet; columns keep their types)
  results.csv   the same table as CSV
  runs/         while a sweep runs: one Parquet file per finished run
  summary.json  counts, runs per second, the best run per headline metric
  sweep_<parameter>.png   headline metrics against each swept parameter
  spec.json     the spec of the last sweep into DIR

A run is identified by ``key``, a hash of the scenario, stop time, transient,
method and all its parameter values.  Each run's row is written to runs/ as it
completes, so an interrupted or killed sweep keeps what it finished; at the end
the rows go into results.parquet and results.csv (harness.sweep.table).
Re-running with the same --out skips every run already in the table
(``--retry-failed`` redoes the failed ones).  A run that fails (an FMU error, a rejected
parameter value, a NaN metric) is recorded as failed with its message; the sweep goes on.
If the FMUs are rebuilt with different behaviour, sweep into a new DIR.

The spec's shape is checked against a JSON Schema (harness.sweep.schema; print it
with python -m harness.sweep.schema), then its names and values.  Limits
(harness.sweep.spec): at most 100000 runs per spec (counted from its
sizes before anything is built), stop_time at most 10^4 s; every value is
checked first (finite, Integers integral and in range, never wrapped).  One
sweep at a time writes DIR (a lock, harness.sweep.lock); a second one is
refused.  Exit status: 0 every run of the spec ok, 1 some failed (see
the table), 2 a bad spec or no cluster, 3 DIR is locked by another sweep.
"""
from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

# name -> the part that defines it; loaded on first use, so that running a part
# (python -m harness.sweep.schema) does not import it twice
_EXPORTS = {
    "ClusterError": "spec", "SpecError": "spec", "FMUWorkerPlugin": "cluster",
    "SweepSpec": "plan", "load_spec": "plan", "parse_spec": "plan",
    "SweepResult": "run", "add_arguments": "run", "cmd_sweep": "run", "main": "run",
    "register": "run", "run_sweep": "run",
    "SimulationPool": "simulation", "prepare": "simulation", "simulate": "simulation",
    "ResultsTable": "table", "result_row": "table",
}
__all__ = [
    "ClusterError", "FMUWorkerPlugin", "ResultsTable", "SimulationPool", "SpecError",
    "SweepResult", "SweepSpec", "add_arguments", "cmd_sweep", "load_spec", "main",
    "parse_spec", "prepare", "register", "result_row", "run_sweep", "simulate",
]

if TYPE_CHECKING:
    from .cluster import FMUWorkerPlugin
    from .plan import SweepSpec, load_spec, parse_spec
    from .run import SweepResult, add_arguments, cmd_sweep, main, register, run_sweep
    from .simulation import SimulationPool, prepare, simulate
    from .spec import ClusterError, SpecError
    from .table import ResultsTable, result_row


def __getattr__(name: str) -> Any:
    if name not in _EXPORTS:
        raise AttributeError(f"module 'harness.sweep' has no attribute {name!r}")
    value = getattr(import_module(f"{__name__}.{_EXPORTS[name]}"), name)
    globals()[name] = value
    return value
