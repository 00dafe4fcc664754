"""A sweep specification read into its runs (see harness.sweep for the format).

:func:`load_spec` reads a JSON or TOML file, :func:`parse_spec` checks it --
its shape against the JSON Schema (harness.sweep.schema), then every name
against the scenarios and the FMUs' model descriptions and every value
(harness.sweep.spec) -- and
gives a :class:`SweepSpec`, whose :meth:`SweepSpec.runs` lists the runs, each
identified by a hash of everything that determines its result.
"""
from __future__ import annotations

import hashlib
import itertools
import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..fmus import Value, Variable, variables_of
from ..paths import default_fmu_dir
from .schema import METHODS, check_shape
from .spec import (
    MAX_STOP_TIME,
    PSEUDO,
    RandomSampling,
    Range,
    SpecError,
    check_run_count,
    convert_value,
    count,
    mapping,
    positive,
    pseudo_value,
    run_count_bound,
    sampling_seed,
    value_range,
)
from .spec import transient as check_transient

DEFAULT_FMU_DIR = default_fmu_dir()
FMU_FILES = {"plant": "Pendulum.fmu", "controller": "TwistingController.fmu",
             "observer": "SuperTwistingObserver.fmu"}
METRICS_WINDOW = 1.0  # harness.metrics.score: max_e2_after_1s etc. use t >= 1 s


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
    """Validates a spec (a dict as read from JSON/TOML): its shape against the schema
    (harness.sweep.schema), then against the scenarios and FMUs (every value, and the
    number of runs: harness.sweep.spec)."""
    from ..scenarios import SCENARIOS

    check_shape(data)
    name = data["scenario"]
    scenario = SCENARIOS[name]
    stop_time = positive(data.get("stop_time", scenario.stop_time), "stop_time", MAX_STOP_TIME)
    transient = check_transient(data.get("transient", scenario.transient))
    # harness.metrics.score looks at t >= 1 s and t >= transient: both must hold data.
    if not stop_time > max(METRICS_WINDOW, transient):
        raise SpecError(f"stop_time = {stop_time:g} s: the metrics need a run longer than "
                        f"{METRICS_WINDOW:g} s (their fixed window t >= 1 s) and than the "
                        f"transient ({transient:g} s; override it with \"transient\")")
    method = data.get("method", METHODS[0])

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

    fixed = {k: typed(k, v, "fixed") for k, v in data.get("fixed", {}).items()}
    grid = {k: [typed(k, v, "grid") for v in values] for k, values in data.get("grid", {}).items()}

    random = None
    if "random" in data:
        r = data["random"]
        n = count(r["n"], "random.n")
        ranges: dict[str, Range] = {}
        for k, spec in r["ranges"].items():
            var = declared.setdefault(k, _parameter(k, variables))
            if var.type == "Boolean":
                raise SpecError(f"random.ranges: {k!r} is a Boolean; put it in the grid")
            if k in grid:
                raise SpecError(f"{k!r} is both in the grid and in random.ranges")
            ranges[k] = value_range(k, spec, var.type, var.min, var.max)
        random = RandomSampling(r.get("method", "lhs"), n, sampling_seed(r.get("seed", 0)), ranges)

    points = [{k: typed(k, v, f"points[{i}]") for k, v in point.items()}
              for i, point in enumerate(data.get("points", []))]

    seeds = None
    if "seeds" in data:
        raw = data["seeds"]
        if isinstance(raw, int) and not isinstance(raw, bool):
            raw = list(range(count(raw, "seeds")))  # a count: checked before the list is made
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
    """The spec of a JSON (or .toml) file, read by harness.inputs (bounded size and
    depth, UTF-8, no duplicate keys), then checked (parse_spec)."""
    from ..inputs import InputError, read_structured

    path = Path(path)
    try:
        data = read_structured(path, "sweep spec")
    except InputError as error:
        raise SpecError(str(error)) from None
    try:
        return parse_spec(mapping(data, str(path)), fmu_dir)
    except SpecError as error:
        raise SpecError(f"{path}: {error}") from None

