"""Offline identification: a recorded experiment (t, y, u) fed through the observer FMU.

:func:`identify` runs a recording held in memory; :func:`identify_file` streams a
CSV log of any length block by block (see :mod:`harness.recording` for what it
reads), writing the estimates as it goes, so that memory does not grow with the
log.  Both return the observer's outputs at every sample; the trust outputs
(``converged``, ``identifier_active``, ``excitation``, the standard errors and
the estimated noise) say how far to believe them.
"""
from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .fmus import FMUInstance, Value
from .master import CoSimulation, Link, initialize, run
from .recording import Block, DataError, ReadOptions, Recording, read_blocks, read_recording

__all__ = ["DataError", "ReadOptions", "Recording", "read_recording", "identify",
           "identify_file", "held_input", "final_estimates", "Summary"]

OUTPUTS = ["x1_hat[1]", "x2_hat[1]", "z_eq[1]", "z_eq_filtered[1]"] + \
          [f"theta_hat[1,{k}]" for k in range(1, 6)] + \
          [f"theta_std[1,{k}]" for k in range(1, 6)] + \
          ["b_hat", "b_std", "gamma_trace", "noise_std[1]", "observer_bandwidth[1]", "excitation"]
FLAGS = ("converged", "identifier_active")  # Booleans: read at the end of the record
PLOT_POINTS = 20_000  # identify_file keeps at most twice this many rows for the figure


INPUT_HOLDS = ("zoh", "sampled")


def held_input(u: np.ndarray, input_hold: str) -> np.ndarray:
    """The input as the FMU takes it: constant over each sample interval (FMI's
    piecewise-constant inputs).

    ``"zoh"``: u[k] was applied over [t_k, t_k+1) (a digital controller's
    command).  ``"sampled"``: u[k] is a sample of a continuous signal (a measured
    torque, a plant driven by a smooth input); its mean over [t_k, t_k+1) is
    (u[k] + u[k+1]) / 2 to O(h^2).  Taking a sampled input as held shifts it by
    half a sample, which biases the identified viscous coefficient by O(h)
    (measured: 13.7 % at 1 kHz, open-loop multi-sine)."""
    if input_hold == "zoh":
        return u
    if input_hold == "sampled":
        return np.concatenate([0.5 * (u[:-1] + u[1:]), u[-1:]])
    raise ValueError(f"input_hold = {input_hold!r}: expected one of {', '.join(INPUT_HOLDS)}")


def _column(name: str) -> str:
    """The output's column name: joint 1's vectors without the index."""
    return name.replace("[1]", "")


class _Run:
    """The observer FMU over consecutive blocks of one recording (sample step ``step``).

    Each block gives the outputs at its own samples: the first sample's after
    initialization, every other one's after the step from the sample before it."""

    def __init__(self, observer_fmu: Path, parameters: Mapping[str, Value], step: float,
                 input_hold: str):
        if input_hold not in INPUT_HOLDS:
            held_input(np.zeros(1), input_hold)  # raises the message
        self.observer = FMUInstance(observer_fmu, "observer")
        self.sim = CoSimulation({"observer": self.observer},
                                [Link("signal:y", "observer.y[1]"), Link("signal:u", "observer.u")])
        # a sample period longer than the observer's largest step: several internal steps
        # per sample, which the FMU is told so that it does not report them as a staircase
        self.parameters = {"h": default_internal_step(step, self.observer.variable("h").max),
                           "input_period": step, **parameters}
        self.step, self.input_hold = step, input_hold
        self.k = 0  # index of the next sample to step from
        self.carry: tuple[float, float] | None = None  # (y, u) of the last sample so far

    def feed(self, y: np.ndarray, u: np.ndarray) -> dict[str, np.ndarray]:
        """The outputs at these samples (the next ones of the recording)."""
        if self.carry is not None:
            y = np.concatenate([[self.carry[0]], y])
            u = np.concatenate([[self.carry[1]], u])
        signals = {"y": y[:-1], "u": held_input(u, self.input_hold)[:-1]}
        start = self.k * self.step
        if self.carry is None:
            first = {"y": y, "u": held_input(u, self.input_hold)}
            initialize(self.sim, 0.0, {"observer": self.parameters}, first)
        n = len(y) - 1
        records = run(self.sim, start, start + n * self.step, self.step,
                      [f"observer.{o}" for o in OUTPUTS], signals=signals)
        skip = 0 if self.carry is None else 1  # the row of the carried sample is out already
        self.k += n
        self.carry = (float(y[-1]), float(u[-1]))
        return {_column(o): records[f"observer.{o}"][skip:] for o in OUTPUTS}

    def flags(self) -> dict[str, bool]:
        return {name: bool(value) for name, value in zip(FLAGS, self.observer.get(FLAGS))}

    def close(self) -> None:
        self.sim.close()


def identify(recording: Recording, observer_fmu: Path, parameters: Mapping[str, Value],
             input_hold: str = "zoh") -> dict[str, np.ndarray]:
    """Run the observer over the recording; returns t, y, u and the observer outputs
    (joint 1's, named without the index: x2_hat, theta_hat[1,2], excitation, ...) and
    the final Booleans ``converged`` and ``identifier_active`` as 1-element arrays.

    ``input_hold`` says how u was applied between samples (see held_input)."""
    observer = _Run(observer_fmu, parameters, recording.step, input_hold)
    try:
        out = {"t": recording.t, "y": recording.y, "u": recording.u,
               **observer.feed(recording.y, recording.u)}
        out.update({name: np.array([flag]) for name, flag in observer.flags().items()})
    finally:
        observer.close()
    return out


@dataclass
class Summary:
    """What identify_file found: the final estimates and how far to trust them."""

    final: dict[str, float]
    standard_error: dict[str, float]
    noise_std: float
    excitation: float
    converged: bool
    identifier_active: bool
    samples: int
    step: float  # [s]
    h: float  # the observer's internal step [s]
    first_stamp: str  # the first time stamp as written
    fmu_warnings: list[str] = field(default_factory=list)
    figure_rows: dict[str, np.ndarray] = field(default_factory=dict, repr=False)

    @property
    def trusted(self) -> bool:
        """The observer converged and the FMU did not warn."""
        return self.converged and not self.fmu_warnings

    def as_json(self) -> dict[str, object]:
        return {"final": self.final, "standard_error": self.standard_error,
                "noise_std": self.noise_std,
                "trust": {"converged": self.converged,
                          "identifier_active": self.identifier_active,
                          "excitation": self.excitation, "fmu_warnings": self.fmu_warnings},
                "samples": self.samples, "step": self.step, "h": self.h,
                "first_stamp": self.first_stamp}


def identify_file(path: str | Path, observer_fmu: Path, parameters: Mapping[str, Value],
                  out_csv: str | Path | None = None, *, options: ReadOptions | None = None,
                  input_hold: str = "zoh", decimation: int = 1) -> Summary:
    """Streams the recording at ``path`` through the observer: writes t (as written in
    the file), y, u and the outputs of every ``decimation``-th sample to ``out_csv``
    and returns the Summary (with at most 2 * PLOT_POINTS rows kept for a figure)."""
    from .background import WriteBehind, read_ahead
    from .tables import CsvStream

    if decimation < 1:
        raise ValueError(f"decimation {decimation} must be >= 1")
    blocks = read_ahead(read_blocks(path, options))
    first = next(blocks)
    observer: _Run | None = None
    kept = _Thinned(PLOT_POINTS)
    index = 0
    last: dict[str, float] = {}
    step = _block_step(first)
    try:
        with CsvStream(out_csv) if out_csv else _NoStream() as stream, \
                WriteBehind(stream.write) as writer:
            for block in _chain(first, blocks):
                if observer is None:
                    observer = _Run(Path(observer_fmu), parameters, step, input_hold)
                outputs = observer.feed(block.y, block.u)
                columns = {"y": block.y, "u": block.u, **outputs}
                writer.put(_every(decimation, index, block.stamps, columns))
                kept.add(index, {"t": block.time, **columns})
                last = {k: float(v[-1]) for k, v in (("t", block.time), *columns.items())}
                index += len(block.y)
            assert observer is not None  # the first block made it
            flags = observer.flags()
            warnings = observer.observer.warnings()
            h = float(observer.parameters["h"])
    finally:
        if observer is not None:
            observer.close()
    estimates = final_estimates({k: np.array([v]) for k, v in last.items()})
    return Summary(estimates["final"], estimates["standard_error"], estimates["noise_std"],
                   last["excitation"], flags["converged"], flags["identifier_active"], index,
                   step, h, str(first.stamps[0].as_py()), warnings, kept.columns())


def _every(decimation: int, index: int, stamps, columns: Mapping[str, np.ndarray]
           ) -> dict[str, object]:
    """The rows of a block (its first one the recording's row ``index``) whose row number
    is a multiple of ``decimation``: t (the stamps as written) and the columns."""
    if decimation == 1:
        return {"t": stamps, **columns}
    from .tables import as_arrow

    chosen = np.arange(-index % decimation, len(stamps), decimation, dtype=np.int64)
    return {"t": stamps.take(as_arrow(chosen)), **{k: v[chosen] for k, v in columns.items()}}


def _block_step(block: Block) -> float:
    """The sampling step of a recording from its first block (its median step)."""
    if len(block.time) < 2:
        raise DataError("the recording's first block has fewer than 2 samples")
    return float(np.median(np.diff(block.time[:1001])))


def _chain(first: Block, rest: Iterable[Block]):
    yield first
    yield from rest


class _NoStream:
    def write(self, columns) -> None:
        pass

    def __enter__(self) -> _NoStream:
        return self

    def __exit__(self, *exc) -> None:
        pass


class _Thinned:
    """Every stride-th row of a long series, the stride doubled whenever more than
    2 * limit rows are kept (so that at most that many are)."""

    def __init__(self, limit: int):
        self.limit, self.stride = limit, 1
        self.parts: list[dict[str, np.ndarray]] = []
        self.count = 0

    def add(self, start: int, columns: Mapping[str, np.ndarray]) -> None:
        """The next rows of the series, the first one its row ``start``."""
        first = -start % self.stride  # the first row of these that is a multiple of stride
        part = {k: np.asarray(v)[first::self.stride].copy() for k, v in columns.items()}
        self.parts.append(part)
        self.count += len(next(iter(part.values())))
        if self.count > 2 * self.limit:
            merged = self.columns()
            self.stride *= 2
            self.parts = [{k: v[::2] for k, v in merged.items()}]
            self.count = len(next(iter(self.parts[0].values())))

    def columns(self) -> dict[str, np.ndarray]:
        if not self.parts:
            return {}
        return {k: np.concatenate([p[k] for p in self.parts]) for k in self.parts[0]}


def default_internal_step(step: float, h_max: float | None) -> float:
    """The observer's h when the user gives none: the sample step itself
    (sub-stepping would hold y constant over a sample, a staircase the observer
    then tracks), or, for samples further apart than the largest h the FMU
    accepts (``h_max``, 1 s), the sample step split into the fewest equal
    internal steps that fit."""
    if h_max is None or step <= h_max:
        return step
    return step / math.ceil(step / h_max)


def final_estimates(columns: Mapping[str, np.ndarray]) -> dict[str, Any]:
    """The estimates at the end of the record with their standard errors (1 sigma) and
    the estimated measurement noise."""
    names = [f"theta_hat[1,{k}]" for k in range(1, 6)] + ["b_hat"]
    errors = [f"theta_std[1,{k}]" for k in range(1, 6)] + ["b_std"]
    return {"final": {n: float(columns[n][-1]) for n in names},
            "standard_error": {n: float(columns[e][-1]) for n, e in zip(names, errors)},
            "noise_std": float(columns["noise_std"][-1])}
