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
  results.csv   one row per run: key, status (ok/failed), message, wall_time [s],
                worker, scenario, stop_time, method, every run parameter, every metric
  summary.json  counts, runs per second, the best run per headline metric
  sweep_<parameter>.png   headline metrics against each swept parameter
  spec.json     the spec of the last sweep into DIR

A run is identified by ``key``, a hash of the scenario, stop time, transient,
method and all its parameter values.  Rows are appended as runs complete, so an
interrupted sweep keeps what it finished; re-running with the same --out skips
every run whose key is already in results.csv (``--retry-failed`` redoes the
failed ones).  A run that fails (an FMU error, a rejected parameter value, a
NaN metric) is recorded as failed with its message; the sweep goes on.
If the FMUs are rebuilt with different behaviour, sweep into a new DIR.

Limits (harness.sweep_spec): at most 100000 runs per spec (counted from its
sizes before anything is built), stop_time at most 10^4 s; every value is
checked first (finite, Integers integral and in range, never wrapped).  One
sweep at a time writes DIR (a lock, harness.sweep_lock); a second one is
refused.  Exit status: 0 every run of the spec ok, 1 some failed (see
results.csv), 2 a bad spec or no cluster, 3 DIR is locked by another sweep.
"""
from __future__ import annotations

import argparse
import csv
import dataclasses
import hashlib
import io
import itertools
import json
import math
import os
import shutil
import signal
import sys
import tempfile
import threading
import time
import uuid
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .fmus import FMUError, Value, Variable, variables_of
from .paths import default_fmu_dir
from .sweep_lock import OutputLocked, locked_output
from .tempdirs import owned_temp_dir, remove_stale
from .values import argparse_type, integer, real
from .sweep_spec import (MAX_STOP_TIME, PSEUDO, RandomSampling, Range, SpecError,
                         check_run_count, convert_value, count, mapping, positive, pseudo_value,
                         run_count_bound, sampling_seed, value_range)
from .sweep_spec import transient as check_transient

DEFAULT_FMU_DIR = default_fmu_dir()
FMU_FILES = {"plant": "Pendulum.fmu", "controller": "TwistingController.fmu",
             "observer": "SuperTwistingObserver.fmu"}
METHODS = ("paper", "improved")
MAX_WORKERS = 1024  # --workers: LocalCluster processes on this machine
CONNECT_TIMEOUT = 30.0  # s: to reach a scheduler, and for its first worker
TABLE = "results.csv"
METRICS_WINDOW = 1.0  # harness.metrics.score: max_e2_after_1s etc. use t >= 1 s


# ---- the specification ---------------------------------------------------------

@dataclass(frozen=True)
class Run:
    key: str
    params: dict[str, Value]  # every parameter of the run, fixed and swept


@dataclass
class SweepSpec:
    scenario: str
    stop_time: float
    transient: float
    method: str = "paper"
    fixed: dict[str, Value] = field(default_factory=dict)
    grid: dict[str, list[Value]] = field(default_factory=dict)
    random: RandomSampling | None = None
    points: list[dict[str, Value]] = field(default_factory=list)
    seeds: list[int] | None = None
    types: dict[str, str] = field(default_factory=dict)  # parameter -> Real/Integer/Boolean
    source: dict[str, Any] = field(default_factory=dict)  # the spec as read

    @property
    def swept(self) -> list[str]:
        """Parameters that vary from run to run (in spec order)."""
        names = list(self.grid)
        if self.random:
            names += [n for n in self.random.ranges if n not in names]
        for point in self.points:
            names += [n for n in point if n not in names]
        if self.seeds is not None and len(self.seeds) > 1 and "seed" not in names:
            names.append("seed")
        return names

    def runs(self) -> list[Run]:
        """Every run, in a deterministic order, duplicates removed."""
        combos: list[dict[str, Value]] = []
        grid_names = list(self.grid)
        grid = [dict(zip(grid_names, values))
                for values in itertools.product(*(self.grid[n] for n in grid_names))]
        if self.random:
            names = list(self.random.ranges)
            samples = [{n: self._sampled(n, float(x)) for n, x in zip(names, row)}
                       for row in self.random.sample()]
            combos = [{**g, **s} for g in grid for s in samples]
        elif self.grid or not self.points:
            combos = grid  # [{}] when there is no grid: the scenario itself
        combos += [dict(p) for p in self.points]
        seeds = self.seeds if self.seeds is not None else [None]
        runs: list[Run] = []
        seen: set[str] = set()
        for combo in combos:
            for seed in seeds:
                params: dict[str, Value] = {"noise_std": 0.0, "seed": 0, **self.fixed, **combo}
                if seed is not None:
                    params["seed"] = seed
                if params["noise_std"] == 0.0:
                    params["seed"] = 0  # the seed only seeds the noise: one noise-free run
                key = run_key(self.scenario, self.stop_time, self.transient, self.method, params)
                if key not in seen:
                    seen.add(key)
                    runs.append(Run(key, params))
        return runs

    def _sampled(self, name: str, value: float) -> Value:
        """A sample of a random range as the parameter's type (Integers rounded)."""
        return convert_value(name, self.types[name], value, sampled=True)


def run_key(scenario: str, stop_time: float, transient: float, method: str,
            params: Mapping[str, Value]) -> str:
    """The run's identity: a hash of everything that determines its result."""
    canonical = json.dumps({"scenario": scenario, "stop_time": float(stop_time),
                            "transient": float(transient), "method": method,
                            "params": {k: params[k] for k in sorted(params)}},
                           sort_keys=True, allow_nan=True)
    return hashlib.sha256(canonical.encode()).hexdigest()[:16]


def parameter_types(fmu_dir: Path) -> dict[str, dict[str, Variable]]:
    """fmu -> variable name -> Variable (type, causality, declared range), read from
    the FMUs' model descriptions."""
    from fmpy import read_model_description

    out: dict[str, dict[str, Variable]] = {}
    for fmu, filename in FMU_FILES.items():
        path = fmu_dir / filename
        if not path.exists():
            raise SpecError(f"{path} is missing: run ./build.sh fmus first (or pass --fmu-dir)")
        out[fmu] = variables_of(read_model_description(str(path)))
    return out


def _parameter(name: str, variables: Mapping[str, Mapping[str, Variable]]) -> Variable:
    if name in PSEUDO:
        return Variable(name, -1, "Real" if name == "noise_std" else "Integer", "parameter")
    fmu, _, variable = name.partition(".")
    if fmu not in variables or not variable:
        raise SpecError(f"{name!r}: a parameter is 'fmu.variable' with fmu one of "
                        f"{', '.join(FMU_FILES)} (or one of {', '.join(PSEUDO)})")
    if variable not in variables[fmu]:
        raise SpecError(f"{name!r}: {FMU_FILES[fmu]} has no variable {variable!r}")
    causality = variables[fmu][variable].causality
    if causality != "parameter":
        raise SpecError(f"{name!r} is {'an' if causality[0] in 'aeiou' else 'a'} {causality}, "
                        f"not a parameter")
    return variables[fmu][variable]


def parse_spec(data: Mapping[str, Any], fmu_dir: Path = DEFAULT_FMU_DIR) -> SweepSpec:
    """Validates a spec (a dict as read from JSON/TOML) against the scenarios and FMUs
    (every value, and the number of runs: harness.sweep_spec)."""
    from .scenarios import SCENARIOS

    known = {"scenario", "stop_time", "transient", "method", "fixed", "grid", "random", "points",
             "seeds", "description"}
    unknown = set(data) - known
    if unknown:
        raise SpecError(f"unknown spec keys {sorted(unknown)}; known: {sorted(known)}")
    name = data.get("scenario")
    if not isinstance(name, str) or name not in SCENARIOS:
        raise SpecError(f"scenario {name!r} is not one of {', '.join(SCENARIOS)}")
    scenario = SCENARIOS[name]
    stop_time = positive(data.get("stop_time", scenario.stop_time), "stop_time", MAX_STOP_TIME)
    transient = check_transient(data.get("transient", scenario.transient))
    # harness.metrics.score looks at t >= 1 s and t >= transient: both must hold data.
    if not stop_time > max(METRICS_WINDOW, transient):
        raise SpecError(f"stop_time = {stop_time:g} s: the metrics need a run longer than "
                        f"{METRICS_WINDOW:g} s (their fixed window t >= 1 s) and than the "
                        f"transient ({transient:g} s; override it with \"transient\")")
    method = data.get("method", "paper")
    if not isinstance(method, str) or method not in METHODS:
        raise SpecError(f"method {method!r} is not one of {', '.join(METHODS)}")

    variables = parameter_types(fmu_dir)
    declared: dict[str, Variable] = {}

    def typed(name: str, value: Any, where: str) -> Value:
        if name not in declared:
            declared[name] = _parameter(name, variables)
        var = declared[name]
        try:
            if name in PSEUDO:
                return pseudo_value(name, value)
            return convert_value(name, var.type, value, low=var.min, high=var.max)
        except SpecError as error:
            raise SpecError(f"{where}: {error}") from None

    fixed = {k: typed(k, v, "fixed") for k, v in mapping(data.get("fixed", {}), "fixed").items()}
    grid: dict[str, list[Value]] = {}
    for k, values in mapping(data.get("grid", {}), "grid").items():
        if not isinstance(values, list) or not values:
            raise SpecError(f"grid: {k!r} needs a non-empty list of values")
        grid[k] = [typed(k, v, "grid") for v in values]

    random = None
    if "random" in data:
        r = mapping(data["random"], "random")
        extra = set(r) - {"method", "n", "seed", "ranges"}
        if extra:
            raise SpecError(f"random: unknown keys {sorted(extra)}")
        sampling = r.get("method", "lhs")
        if sampling not in ("lhs", "uniform"):
            raise SpecError(f"random: method {sampling!r} is not 'lhs' or 'uniform'")
        n = count(r.get("n"), "random: n")
        ranges: dict[str, Range] = {}
        for k, spec in mapping(r.get("ranges", {}), "random.ranges").items():
            var = declared.setdefault(k, _parameter(k, variables))
            if var.type == "Boolean":
                raise SpecError(f"random.ranges: {k!r} is a Boolean; put it in the grid")
            if k in grid:
                raise SpecError(f"{k!r} is both in the grid and in random.ranges")
            ranges[k] = value_range(k, spec, var.type, var.min, var.max)
        if not ranges:
            raise SpecError("random: ranges is empty")
        random = RandomSampling(sampling, n, sampling_seed(r.get("seed", 0)), ranges)

    raw_points = data.get("points", []) or []
    if not isinstance(raw_points, list):
        raise SpecError("points: give a list of tables/objects")
    points = []
    for i, point in enumerate(raw_points):
        point = mapping(point, f"points[{i}]")
        points.append({k: typed(k, v, f"points[{i}]") for k, v in point.items()})

    seeds = None
    if "seeds" in data:
        raw = data["seeds"]
        if isinstance(raw, int) and not isinstance(raw, bool):
            raw = list(range(count(raw, "seeds")))  # a count: checked before the list is made
        if not isinstance(raw, list) or not raw:
            raise SpecError("seeds: give a non-empty list of integers or a count")
        seeds = [int(typed("seed", s, "seeds")) for s in raw]
        if "seed" in grid or (random and "seed" in random.ranges):
            raise SpecError("give the noise seeds either as 'seeds' or as a 'seed' parameter")
    check_run_count(run_count_bound([len(v) for v in grid.values()],
                                    random.n if random else None, len(points),
                                    len(seeds) if seeds is not None else 1))
    types = {k: v.type for k, v in declared.items()}
    spec = SweepSpec(name, stop_time, transient, method, fixed, grid, random, points, seeds,
                     types, dict(data))
    if not spec.runs():
        raise SpecError("the spec describes no run")
    return spec


def load_spec(path: str | Path, fmu_dir: Path = DEFAULT_FMU_DIR) -> SweepSpec:
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as error:
        raise SpecError(f"{path}: {error.strerror}") from None
    try:
        if path.suffix == ".toml":
            import tomllib  # Python >= 3.11

            data = tomllib.loads(text)
        else:
            data = json.loads(text)
    except ImportError:
        raise SpecError(f"{path}: TOML needs Python >= 3.11; use JSON") from None
    except ValueError as error:  # JSONDecodeError, TOMLDecodeError
        raise SpecError(f"{path}: {error}") from None
    try:
        return parse_spec(mapping(data, str(path)), fmu_dir)
    except SpecError as error:
        raise SpecError(f"{path}: {error}") from None


# ---- one run, on a worker ----------------------------------------------------

def prepare(spec: SweepSpec, run: Run):
    """The Scenario of one run (all overrides applied), its noise std and seed."""
    from .scenarios import SCENARIOS, improved_overrides

    base = SCENARIOS[spec.scenario]
    noise_std = float(run.params.get("noise_std", 0.0))
    seed = int(run.params.get("seed", 0))
    parts: dict[str, dict[str, Value]] = {"plant": dict(base.plant),
                                          "controller": dict(base.controller),
                                          "observer": dict(base.observer)}
    if spec.method == "improved":
        parts["observer"].update(improved_overrides(base, noise_std))
    for name, value in run.params.items():
        if name in PSEUDO:
            continue
        fmu, _, variable = name.partition(".")
        parts[fmu][variable] = value
    # Overrides go into the Scenario itself: the metrics read the true and
    # nominal coefficients (plant.Vs, observer.c_nominal[k], ...) from it.
    scenario = dataclasses.replace(base, stop_time=spec.stop_time, transient=spec.transient,
                                   **parts)
    return scenario, noise_std, seed


class SimulationPool:
    """Closed-loop co-simulations of one process, built once and reused.

    Each co-simulation instantiates the three FMUs (extracting them once);
    between runs the instances go back to their start values by fmi2Reset.
    A thread takes one co-simulation for the duration of a run, so a worker
    with several threads uses one co-simulation per thread."""

    def __init__(self, fmu_dir: Path):
        self.fmu_dir = Path(fmu_dir)
        self._free: list = []
        self._all: list = []
        self._lock = threading.Lock()

    def acquire(self):
        from .scenarios import SCENARIOS, build

        with self._lock:
            if self._free:
                return self._free.pop()
        sim = build(next(iter(SCENARIOS.values())), self.fmu_dir)
        with self._lock:
            self._all.append(sim)
        return sim

    def release(self, sim, healthy: bool) -> None:
        with self._lock:
            if healthy:
                self._free.append(sim)
                return
            self._all.remove(sim)
        sim.close()

    def close(self) -> None:
        with self._lock:
            sims, self._all, self._free = self._all, [], []
        for sim in sims:
            try:
                sim.close()
            except Exception:  # noqa: BLE001 - closing is best effort
                pass

    @property
    def size(self) -> int:
        return len(self._all)


def simulate(pool: SimulationPool, scenario, noise_std: float, seed: int,
             use_native: bool | None = None) -> dict[str, Any]:
    """One scored run on a pooled co-simulation: what scenarios.run_scenario + score do.

    Never raises for a failed run: returns status "failed" and the message."""
    from .metrics import score
    from .scenarios import run_on

    start = time.perf_counter()
    result: dict[str, Any] = {"status": "ok", "message": "", "metrics": {}}
    sim = None
    healthy = True
    try:
        sim = pool.acquire()
        for fmu in sim.fmus.values():
            fmu.reset()
        records = run_on(sim, scenario, noise_std=noise_std, seed=seed, use_native=use_native)
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore", RuntimeWarning)
            try:
                metrics = score(scenario, records)
            except (ValueError, IndexError) as error:
                raise _ScoreError(f"scoring failed (is stop_time long enough for the "
                                  f"metrics?): {error}") from None
        result["metrics"] = metrics
        nan = [k for k, v in metrics.items() if isinstance(v, float) and math.isnan(v)]
        if nan:
            result["status"] = "failed"
            result["message"] = f"NaN metric(s): {', '.join(nan)}"
    except (FMUError, _ScoreError) as error:
        result["status"], result["message"] = "failed", str(error)
    except Exception as error:  # noqa: BLE001 - any failure of one run is recorded, not raised
        result["status"], result["message"] = "failed", f"{type(error).__name__}: {error}"
        healthy = False  # unknown state: do not reuse these instances
    finally:
        if sim is not None:
            pool.release(sim, healthy)
    result["wall_time"] = time.perf_counter() - start
    return result


class _ScoreError(RuntimeError):
    pass


# ---- Dask: FMUs shipped to each worker once ----------------------------------

def _fmu_payload(fmu_dir: Path) -> tuple[dict[str, bytes], str]:
    payload = {}
    digest = hashlib.sha256()
    for filename in FMU_FILES.values():
        data = (fmu_dir / filename).read_bytes()
        payload[filename] = data
        digest.update(filename.encode() + b"\0" + data)
    return payload, digest.hexdigest()[:12]


try:
    from distributed.diagnostics.plugin import WorkerPlugin as _WorkerPlugin
except ImportError:  # pragma: no cover - dask is in requirements.txt
    _WorkerPlugin = object


class FMUWorkerPlugin(_WorkerPlugin):
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
    plugin = worker.plugins[plugin_name]
    result = simulate(plugin.pool, scenario, noise_std, seed)
    result["worker"] = str(worker.name)
    return result


# ---- the results table ---------------------------------------------------------

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


# ---- running a sweep -------------------------------------------------------------

class ProgressLine:
    """Runs done, failed, rate and time left on stderr (tqdm; on a file or pipe at most
    one update per 10 s)."""

    def __init__(self, label: str, total: int, stream=None):
        from tqdm import tqdm

        stream = stream or sys.stderr
        tty = hasattr(stream, "isatty") and stream.isatty()
        self.failed = 0
        self.bar = tqdm(total=total, desc=label, file=stream, disable=False,
                        mininterval=0.2 if tty else 10.0, postfix="0 failed",
                        bar_format="{desc}: {n}/{total} runs, {postfix}, {rate_fmt}, "
                                   "{remaining} left", unit="run")

    def update(self, failed: bool) -> None:
        self.failed += failed
        self.bar.set_postfix_str(f"{self.failed} failed", refresh=False)
        self.bar.update(1)
        if self.bar.n >= self.bar.total:
            self.bar.close()


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


class ClusterError(RuntimeError):
    """No Dask cluster to run on: the scheduler cannot be reached or has no workers."""


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


def run_sweep(spec: SweepSpec, out: str | Path, fmu_dir: Path = DEFAULT_FMU_DIR, *,
              scheduler: str | None = None, client=None, n_workers: int | None = None,
              retry_failed: bool = False, plots: bool = True, progress: bool = True,
              stream=None, connect_timeout: float = CONNECT_TIMEOUT) -> SweepResult:
    """Runs the spec's missing runs on Dask and appends them to DIR/results.csv.

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
    table = ResultsTable(out / TABLE)
    (out / "spec.json").write_text(json.dumps(spec.source, indent=2, default=str) + "\n")
    runs = spec.runs()
    done = table.status()
    todo = [r for r in runs if r.key not in done or (retry_failed and done[r.key] != "ok")]
    resumed = len(runs) - len(todo)

    failures: list[tuple[str, str]] = []
    ok = failed = workers = 0
    wall = 0.0
    if todo:
        own = client is None
        cluster = None
        if own:
            client, cluster = start_client(scheduler, n_workers, connect_timeout)
        plugin_name = None
        try:
            payload, digest = _fmu_payload(Path(fmu_dir))
            # One plugin per sweep: concurrent sweeps on a shared cluster keep their own.
            plugin_name = f"sto-sweep-fmus-{digest}-{uuid.uuid4().hex[:8]}"
            client.register_plugin(FMUWorkerPlugin(payload, plugin_name), name=plugin_name)
            workers = len(client.scheduler_info().get("workers", {}))
            counter = ProgressLine(f"sweep {spec.scenario}", len(todo), stream) if progress else None
            if progress and resumed:
                stream.write(f"sweep {spec.scenario}: {resumed} of {len(runs)} runs already in "
                             f"{table.path}, running {len(todo)}\n")
            start = time.perf_counter()
            ok, failed, failures = _execute(client, plugin_name, spec, todo, table, counter)
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
    table.reorder([r.key for r in runs])
    written: list[Path] = []
    rows = _typed_rows(table, {r.key for r in runs})
    if plots and rows:
        written = plot_summary(spec, rows, out)
    _write_summary(spec, rows, out, resumed=resumed, executed=len(todo), wall=wall,
                   workers=workers)
    return SweepResult(len(runs), resumed, len(todo), ok, failed, wall, workers, table.path,
                       written, failures, sum(r.get("status") != "ok" for r in rows))


def _execute(client, plugin_name: str, spec: SweepSpec, todo: list[Run], table: ResultsTable,
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


def run_in_process(spec: SweepSpec, fmu_dir: Path = DEFAULT_FMU_DIR,
                   runs: Iterable[Run] | None = None) -> list[dict[str, Any]]:
    """The spec's runs in this process, without Dask (debugging, benchmarks)."""
    pool = SimulationPool(Path(fmu_dir))
    try:
        out = []
        for run in runs if runs is not None else spec.runs():
            scenario, noise_std, seed = prepare(spec, run)
            out.append(result_row(spec, run, simulate(pool, scenario, noise_std, seed)))
        return out
    finally:
        pool.close()


# ---- summary and plots -----------------------------------------------------------

def _number(text: str) -> Any:
    if text in ("True", "False"):
        return text == "True"
    for convert in (int, float):
        try:
            return convert(text)
        except ValueError:
            pass
    return text


def _typed_rows(table: ResultsTable, keys: set[str]) -> list[dict[str, Any]]:
    """The table's rows of these runs, numbers parsed."""
    skip = {"key", "status", "message", "worker", "scenario", "method"}
    return [{k: (v if k in skip else _number(v)) for k, v in r.items() if v != ""}
            for r in table.rows if r["key"] in keys]


def headline_metrics(spec: SweepSpec, rows: list[dict[str, Any]]) -> list[str]:
    from .compare import HEADLINE
    from .scenarios import SCENARIOS

    present = {k for r in rows for k in r}
    return [m for m in HEADLINE[SCENARIOS[spec.scenario].kind] if m in present]


def _write_summary(spec: SweepSpec, rows: list[dict[str, Any]], out: Path, *, resumed: int,
                   executed: int, wall: float, workers: int) -> None:
    ok = [r for r in rows if r.get("status") == "ok"]
    best = {}
    for metric in headline_metrics(spec, rows):
        values = [(r[metric], r) for r in ok if _is_number(r.get(metric))
                  and math.isfinite(r[metric])]
        if values and metric != "delay" and metric != "damping_lag":
            value, r = min(values, key=lambda x: abs(x[0]))
            best[metric] = {"value": value, "key": r["key"],
                            "params": {p: r.get(p) for p in spec.swept}}
    summary = {"scenario": spec.scenario, "stop_time": spec.stop_time, "method": spec.method,
               "runs": len(rows), "ok": len(ok), "failed": len(rows) - len(ok),
               "resumed": resumed, "executed": executed, "wall_time": wall,
               "runs_per_second": executed / wall if wall > 0 else None, "workers": workers,
               "swept": spec.swept, "best": best}
    (out / "summary.json").write_text(json.dumps(summary, indent=2, default=str) + "\n")


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float))  # bool included


def _filename(name: str) -> str:
    return "".join(c if c.isalnum() or c in "._-" else "_" for c in name).strip("_")


def plot_summary(spec: SweepSpec, rows: list[dict[str, Any]], out: Path) -> list[Path]:
    """One figure per swept parameter: each headline metric against it (ok runs as
    dots, coloured by noise level if the noise is swept too; the median per
    distinct value as a line; failed runs as red marks on the axis)."""
    from matplotlib.figure import Figure  # no pyplot: the backend of a session stays

    metrics = headline_metrics(spec, rows)
    swept = [p for p in spec.swept if p != "seed"] or spec.swept
    paths = []
    if not metrics:
        return paths
    for param in swept:
        if len({r[param] for r in rows if _is_number(r.get(param))}) < 2:
            continue  # nothing to plot against
        ncols = min(3, len(metrics))
        nrows = (len(metrics) + ncols - 1) // ncols
        fig = Figure(figsize=(4.2 * ncols, 3.2 * nrows + 0.4), layout="constrained")
        axes = fig.subplots(nrows, ncols, squeeze=False)
        # Colour by noise level when the noise is swept too (the runs differ most by it).
        levels = sorted({r["noise_std"] for r in rows if _is_number(r.get("noise_std"))})
        by_noise = param != "noise_std" and "noise_std" in spec.swept and 1 < len(levels) <= 6
        for ax, metric in zip(axes.flat, metrics):
            points = [(float(r[param]), float(r[metric]), r.get("noise_std")) for r in rows
                      if r.get("status") == "ok" and _is_number(r.get(param))
                      and _is_number(r.get(metric)) and math.isfinite(r[metric])]
            bad = [float(r[param]) for r in rows
                   if r.get("status") != "ok" and _is_number(r.get(param))]
            groups = ([(f"noise {level:g}", level) for level in levels] if by_noise
                      else [("runs", None)])
            all_x: list[float] = []
            all_y: list[float] = []
            for i, (label, level) in enumerate(groups):
                chosen = [(x, y) for x, y, n in points if level is None or n == level]
                if not chosen:
                    continue
                x, y = (np.array(v) for v in zip(*chosen))
                all_x += list(x)
                all_y += list(y)
                ax.plot(x, y, "o", ms=3, alpha=0.6, color=f"C{i}", label=label)
                distinct = np.unique(x)
                if 1 < len(distinct) <= 25 and len(distinct) < len(x):
                    ax.plot(distinct, [np.median(y[x == v]) for v in distinct], "-",
                            color=f"C{i}", lw=1.5)
            if all_x:
                _scale(ax, "x", np.array(all_x + bad))
                _scale(ax, "y", np.array(all_y))
            if bad:
                ax.plot(bad, [0.0] * len(bad), "x", color="red", transform=ax.get_xaxis_transform(),
                        clip_on=False, label=f"failed ({len(bad)})")
            ax.set_xlabel(param)
            ax.set_ylabel(f"{metric} [{metric_unit(metric)}]")
            ax.grid(True, alpha=0.3)
            if points or bad:
                ax.legend(fontsize=7)
        for ax in list(axes.flat)[len(metrics):]:
            ax.set_visible(False)
        n_ok = sum(r.get("status") == "ok" for r in rows)
        fig.suptitle(f"{spec.scenario} ({spec.stop_time:g} s, {spec.method}): {n_ok} ok, "
                     f"{len(rows) - n_ok} failed of {len(rows)} runs", fontsize=10)
        path = out / f"sweep_{_filename(param)}.png"
        fig.savefig(path, dpi=100, bbox_inches="tight")
        paths.append(path)
    return paths


METRIC_UNITS = {"rms_perturbation": "rad/s²", "delay": "s", "max_e2_after_1s": "rad/s",
                "convergence_time": "s", "rms_damping": "1/s", "damping_lag": "s",
                "max_e1_after_1s": "rad", "mean_e2_after_1s": "rad/s"}


def metric_unit(metric: str) -> str:
    """The unit of a harness.metrics.score metric (relative errors: 1)."""
    return METRIC_UNITS.get(metric, "1" if "rel_error" in metric else "?")


def _scale(ax, axis: str, values: np.ndarray) -> None:
    """Log scale when the values are positive and span a decade or more;
    symlog when there are zeros besides such positive values (noise_std = 0)."""
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    positive = values[values > 0]
    setter = ax.set_xscale if axis == "x" else ax.set_yscale
    if len(positive) < 2 or np.any(values < 0) or positive.max() / positive.min() < 9.99:
        ax.ticklabel_format(axis=axis, style="sci", scilimits=(-3, 4), useOffset=False)
        return
    if np.any(values == 0):
        setter("symlog", linthresh=positive.min())
    else:
        setter("log")


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
                              description=__doc__, parents=list(parents),
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
    runs = spec.runs()
    if args.dry_run:
        try:
            done = ResultsTable(out / TABLE).status() if (out / TABLE).exists() else {}
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
        print(f"\nharness sweep: interrupted; the finished runs are in {out / TABLE}: run the "
              f"same command again to resume", file=sys.stderr)
        return 130
    print(f"sweep {spec.scenario}: {result.total} runs, {result.resumed} already done, "
          f"{result.executed} run now: {result.ok} ok, {result.failed} failed"
          + (f", {result.wall_time:.1f} s on {result.workers} "
             f"worker{'s' if result.workers != 1 else ''} "
             f"({result.runs_per_second:.2f} runs/s)" if result.executed else ""))
    print(f"wrote {result.table}, {out / 'summary.json'}"
          + "".join(f", {p.name}" for p in result.plots))
    for key, message in result.failures[:10]:
        print(f"  failed {key}: {message}")
    if len(result.failures) > 10:
        print(f"  ... and {len(result.failures) - 10} more failed runs (see {TABLE})")
    if result.failed_in_table:  # exit status 1: not every run of the spec succeeded
        print(f"harness sweep: {result.failed_in_table} of {result.total} runs failed (see "
              f"{result.table}; --retry-failed runs them again)", file=sys.stderr)
        return 1
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m harness.sweep", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(parser)
    parser.add_argument("--fmu-dir", default=str(DEFAULT_FMU_DIR),
                        help="folder with the three FMUs (default: harness.paths."
                             "default_fmu_dir())")
    args = parser.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
