"""One sweep run: the scenario with the run's overrides, simulated on a pooled
co-simulation and scored (never raising for a failed run)."""
from __future__ import annotations

import dataclasses
import math
import threading
import time
import warnings
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from ..fmus import FMUError, Value
from .plan import DEFAULT_FMU_DIR, Run, SweepSpec
from .spec import PSEUDO
from .table import result_row


def prepare(spec: SweepSpec, run: Run):
    """The Scenario of one run (all overrides applied), its noise std and seed."""
    from ..scenarios import SCENARIOS, improved_overrides

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
                                   plant=parts["plant"], controller=parts["controller"],
                                   observer=parts["observer"])
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
        from ..scenarios import SCENARIOS, build

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
    from ..metrics import score
    from ..scenarios import run_on

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

