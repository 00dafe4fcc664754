"""The pieces of a sweep specification and their checks (see harness.sweep for the format).

Every value of a spec is checked here before any run: numbers finite and in
range (an Integer parameter integral and 32-bit, never wrapped or truncated),
seeds non-negative integers, and the number of runs at most
:data:`MAX_RUNS` -- counted from the spec's sizes, before any run list is
built, so that a 10^9-run spec is refused at once instead of filling the
memory.
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..fmus import Value
from ..values import INT32_MAX, INT32_MIN, BadValue, fmi_value, integer, real

# The most runs one sweep may have: a run is a closed-loop scenario of at least
# a second of model time (0.1 s or more of wall time), so 10^5 runs is hours on
# a cluster; a larger study is several sweeps (into one --out, they resume).
MAX_RUNS = 100_000
# The longest run: a run records 15 signals at the 1e-4 s communication step,
# 12 MB per 100 s of model time; 10^4 s is 1.2 GB on a worker.
MAX_STOP_TIME = 10_000.0
SEED_MAX = 2**63 - 1  # numpy's generators take any non-negative integer; keep it 64-bit
PSEUDO = ("noise_std", "seed")
MAX_WORKERS = 1024  # --workers: LocalCluster processes on this machine
CONNECT_TIMEOUT = 30.0  # s: to reach a scheduler, and for its first worker


class SpecError(ValueError):
    """The sweep specification is invalid (says where and why)."""


class ClusterError(RuntimeError):
    """No Dask cluster to run on: the scheduler cannot be reached or has no workers."""


@dataclass(frozen=True)
class Range:
    low: float
    high: float
    log: bool = False


@dataclass
class RandomSampling:
    method: str  # "lhs" or "uniform"
    n: int
    seed: int
    ranges: dict[str, Range]

    def sample(self) -> np.ndarray:
        """(n, len(ranges)) samples in [0, 1), then mapped to the ranges."""
        rng = np.random.default_rng(self.seed)
        d = len(self.ranges)
        if self.method == "lhs":  # one sample in each of n strata, per dimension
            from scipy.stats import qmc

            u = qmc.LatinHypercube(d, rng=rng).random(self.n)
        else:
            u = rng.random((self.n, d))
        out = np.empty_like(u)
        for j, r in enumerate(self.ranges.values()):
            if r.log:
                out[:, j] = 10.0 ** (math.log10(r.low) + u[:, j] * (math.log10(r.high) -
                                                                     math.log10(r.low)))
            else:
                out[:, j] = r.low + u[:, j] * (r.high - r.low)
        return out


def convert_value(name: str, type_: str, value: Any, *, sampled: bool = False,
                  low: float | None = None, high: float | None = None) -> Value:
    """A spec value as the parameter's type (Real, Integer, Boolean) within the
    declared range [low, high] of an Integer; SpecError if it cannot be one.

    Only a value ``sampled`` from a random range is rounded to an Integer; a
    value written in the spec must be integral already."""
    if type_ != "Boolean" and (isinstance(value, bool) or not isinstance(value, (int, float))):
        raise SpecError(f"{name}: {value!r} is not a number")
    try:
        if type_ == "Integer":
            return fmi_value(name, "Integer", value, low, high, round_floats=sampled)
        return fmi_value(name, type_, value)
    except BadValue as error:
        raise SpecError(str(error)) from None


def pseudo_value(name: str, value: Any) -> Value:
    """noise_std: a finite number >= 0; seed: an integer in 0 .. 2^63 - 1."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SpecError(f"{name}: {value!r} is not a number")
    try:
        if name == "noise_std":
            return real("noise_std", value, 0.0)
        return integer("seed", value, 0, SEED_MAX)
    except BadValue as error:
        raise SpecError(str(error)) from None


def mapping(value: Any, where: str) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise SpecError(f"{where}: expected a table/object, got {type(value).__name__}")
    return value


def _json_number(value: Any, where: str) -> None:
    """A number of the spec itself (JSON/TOML), not text that looks like one."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SpecError(f"{where} = {value!r} is not a number")


def positive(value: Any, where: str, most: float | None = None) -> float:
    """A finite number > 0 (and <= most)."""
    _json_number(value, where)
    try:
        number = real(where, value, 0.0, most, low_open=True)
    except BadValue as error:
        raise SpecError(f"{error} (a number > 0{f' and <= {most:g}' if most else ''})") from None
    return number


def transient(value: Any) -> float:
    """The metrics' transient: a finite number >= 0."""
    _json_number(value, "transient")
    try:
        return real("transient", value, 0.0)
    except BadValue as error:
        raise SpecError(f"{error} (a number >= 0 [s])") from None


def count(value: Any, where: str, most: int = MAX_RUNS) -> int:
    """A count written in the spec (random.n, seeds): an integer in 1 .. most."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise SpecError(f"{where} = {value!r} must be an integer >= 1")
    if not 1 <= value <= most:
        raise SpecError(f"{where} = {value if abs(value) < 10**40 else 'a huge number'} must be "
                        f"an integer in 1 .. {most} (a sweep has at most {MAX_RUNS} runs)")
    return value


def sampling_seed(value: Any) -> int:
    """random.seed: an integer in 0 .. 2^63 - 1."""
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= SEED_MAX:
        shown = value if not isinstance(value, int) or abs(value) < 10**40 else "a huge number"
        raise SpecError(f"random: seed = {shown!r} must be an integer in 0 .. {SEED_MAX}")
    return value


def value_range(name: str, spec: Any, type_: str, low_bound: float | None = None,
                high_bound: float | None = None) -> Range:
    """random.ranges entry: [low, high] or {"low", "high", "scale"}, finite numbers
    (an Integer's inside its declared range and 32-bit)."""
    if isinstance(spec, list) and len(spec) == 2:
        low, high, scale = spec[0], spec[1], "linear"
    elif isinstance(spec, Mapping):
        extra = set(spec) - {"low", "high", "scale"}
        if extra:
            raise SpecError(f"random.ranges.{name}: unknown keys {sorted(extra)}")
        low, high, scale = spec.get("low"), spec.get("high"), spec.get("scale", "linear")
    else:
        raise SpecError(f"random.ranges.{name}: give [low, high] or "
                        f"{{\"low\": .., \"high\": .., \"scale\": \"log\"}}")
    _json_number(low, f"random.ranges.{name}: low")
    _json_number(high, f"random.ranges.{name}: high")
    try:
        low = real(f"random.ranges.{name}: low", low)
        high = real(f"random.ranges.{name}: high", high)
    except BadValue as error:
        raise SpecError(str(error)) from None
    if not low < high:
        raise SpecError(f"random.ranges.{name}: low = {low} must be < high = {high}")
    if scale not in ("linear", "log"):
        raise SpecError(f"random.ranges.{name}: scale {scale!r} is not 'linear' or 'log'")
    if scale == "log" and not low > 0:
        raise SpecError(f"random.ranges.{name}: a log scale needs low > 0")
    if type_ == "Integer":
        lo = INT32_MIN if low_bound is None else max(INT32_MIN, low_bound)
        hi = INT32_MAX if high_bound is None else min(INT32_MAX, high_bound)
        if low < lo or high > hi:
            raise SpecError(f"random.ranges.{name}: [{low:g}, {high:g}] is not inside the "
                            f"Integer's range [{lo:g}, {hi:g}]")
    return Range(low, high, scale == "log")


def run_count_bound(grid_sizes: list[int], samples: int | None, points: int,
                    seeds: int) -> int:
    """How many runs a spec describes at most (before duplicates are removed):
    (grid x samples) + points, each x seeds -- the product of the spec's sizes,
    computed without building anything."""
    combos = 0
    if samples is not None or grid_sizes or not points:
        combos = math.prod(grid_sizes) * (samples if samples is not None else 1)
    return (combos + points) * seeds


def check_run_count(bound: int) -> None:
    if bound > MAX_RUNS:
        raise SpecError(f"the spec describes up to {bound} runs, more than the {MAX_RUNS} a sweep "
                        f"may have (harness.sweep.spec.MAX_RUNS); split it into several sweeps "
                        f"(they can share --out)")
