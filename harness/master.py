"""The co-simulation master: couples FMUs at a fixed communication step H.

Semantics of one macro step k, from t = t0 + k*H to t + H (both loops):

    for each FMU in the step order:
        for each link into it: value = source output now (or signal[k]) + noise[k]
        set the values, then fmi2DoStep(t, H)

With the bench's step order observer -> plant -> controller, the observer
sees y(t) and u(t), the samples that the paper's explicit scheme integrates
over [t, t+H]; the plant integrates with u(t) held; the controller then
computes u(t+H) from the plant's state at t+H.  Initialization follows the
data flow (plant -> controller -> observer), each FMU's inputs set from the
already initialized ones before its fmi2ExitInitializationMode.

Two implementations of the same loop: a native one (native/master_loop.c,
through the FMUs' FMI function pointers) and a plain-Python one, the fallback
and cross-check.  They produce identical records.
"""
from __future__ import annotations

import ctypes
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

import numpy as np

from . import native_loop
from .fmus import FMUError, FMUInstance, Value
from .user_dynamics import AttachedDynamics, StepHook

CALLS = ("fmi2DoStep", "fmi2GetReal", "fmi2SetReal")


@dataclass(frozen=True)
class Link:
    """``source`` is "fmu.variable" or "signal:name"; ``noise`` names a signal added to it."""

    source: str
    target: str
    noise: str | None = None


@dataclass
class Records:
    """Recorded outputs: ``time`` and one array per probe ("fmu.variable")."""

    time: np.ndarray
    signals: dict[str, np.ndarray]

    def __getitem__(self, name: str) -> np.ndarray:
        if name == "time":
            return self.time
        return self.signals[name]

    def to_csv(self, path: str | Path) -> None:
        """time and every probe, full precision, quoted header (harness.tables)."""
        from .tables import write_csv

        write_csv(path, {"time": self.time, **self.signals})


@dataclass
class CoSimulation:
    """FMUs (in data-flow order, used for initialization), links and the step order."""

    fmus: dict[str, FMUInstance]
    links: list[Link]
    step_order: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        if not self.step_order:
            self.step_order = list(self.fmus)
        unknown = set(self.step_order) - set(self.fmus)
        if unknown:
            raise ValueError(f"step order names unknown FMUs: {sorted(unknown)}")
        for link in self.links:
            self._split(link.target)
            if not link.source.startswith("signal:"):
                self._split(link.source)

    def _split(self, path: str) -> tuple[str, str]:
        fmu, _, variable = path.partition(".")
        if fmu not in self.fmus or not variable:
            raise ValueError(f"{path!r} does not name 'fmu.variable' with fmu in {list(self.fmus)}")
        self.fmus[fmu].variable(variable)  # raises a clear KeyError if unknown
        return fmu, variable

    def close(self) -> None:
        for fmu in self.fmus.values():
            fmu.close()


def _signal_name(source: str) -> str | None:
    return source[len("signal:"):] if source.startswith("signal:") else None


def initialize(sim: CoSimulation, start_time: float, parameters: Mapping[str, Mapping[str, Value]],
               signals: Mapping[str, np.ndarray]) -> None:
    """Initialize every FMU in data-flow order, propagating the links once.

    A link from an FMU that is not initialized yet (a feedback loop) is
    skipped: its target keeps the input's start value until the first step."""
    initialized: set[str] = set()
    for name, fmu in sim.fmus.items():
        fmu.setup(start_time, parameters.get(name, {}))
        inputs: dict[str, float] = {}
        for link in sim.links:
            target_fmu, target_var = sim._split(link.target)
            if target_fmu != name:
                continue
            signal = _signal_name(link.source)
            if signal is not None:
                value = float(signals[signal][0])
            else:
                source_fmu, source_var = sim._split(link.source)
                if source_fmu not in initialized:
                    continue
                value = float(sim.fmus[source_fmu].get([source_var])[0])
            if link.noise:
                value += float(signals[link.noise][0])
            inputs[target_var] = value
        fmu.set(inputs)
        fmu.exit_initialization()
        initialized.add(name)


class _Plan:
    """The loop's tables: indices and value references shared by both loops."""

    def __init__(self, sim: CoSimulation, probes: Sequence[str], signals: Mapping[str, np.ndarray],
                 n_steps: int):
        self.names = list(sim.fmus)
        self.index = {name: i for i, name in enumerate(self.names)}
        self.fmus = [sim.fmus[n] for n in self.names]
        self.order = [self.index[n] for n in sim.step_order]
        self.signal_names = list(signals)
        for name, values in signals.items():
            if len(values) < n_steps:
                raise ValueError(f"signal {name!r} has {len(values)} samples, "
                                 f"the run needs {n_steps}")
        self.signals = (np.ascontiguousarray(np.vstack(
            [np.asarray(signals[n], dtype=float)[:n_steps] for n in self.signal_names]))
                        if signals else np.zeros((0, n_steps)))
        # (source_fmu, source_vr, source_signal, noise_signal, target_fmu, target_vr)
        self.links = []
        for link in sim.links:
            target_fmu, target_var = sim._split(link.target)
            signal = _signal_name(link.source)
            if signal is not None:
                if signal not in signals:
                    raise ValueError(f"link from unknown signal {signal!r}")
                source = (-1, 0, self.signal_names.index(signal))
            else:
                source_fmu, source_var = sim._split(link.source)
                source = (self.index[source_fmu], sim.fmus[source_fmu].vr(source_var), -1)
            if link.noise is not None and link.noise not in signals:
                raise ValueError(f"link noise names unknown signal {link.noise!r}")
            noise = self.signal_names.index(link.noise) if link.noise else -1
            self.links.append((*source, noise, self.index[target_fmu],
                               sim.fmus[target_fmu].vr(target_var)))
        self.probes = []
        for probe in probes:
            fmu, variable = sim._split(probe)
            if sim.fmus[fmu].variable(variable).type != "Real":
                raise ValueError(f"probe {probe!r}: only Real outputs can be recorded")
            self.probes.append((self.index[fmu], sim.fmus[fmu].vr(variable)))

    def failure(self, step: int, fmu: int, call: int, t0: float, H: float) -> FMUError:
        instance = self.fmus[fmu]
        what = f"{CALLS[call]} at step {step} (t = {t0 + step * H:.6g} s)"
        return FMUError(instance.describe_failure(what))


def _run_native(plan: _Plan, records: np.ndarray, row: int, t0: float, H: float, k_begin: int,
                k_end: int, decimation: int) -> int:
    dll = native_loop.load()
    fmus = (native_loop.LoopFMU * len(plan.fmus))(*[
        native_loop.LoopFMU(f.component, f.function_address("fmi2DoStep"),
                       f.function_address("fmi2GetReal"), f.function_address("fmi2SetReal"))
        for f in plan.fmus])
    order = (ctypes.c_int * len(plan.order))(*plan.order)
    links = (native_loop.LoopLink * max(1, len(plan.links)))(
        *[native_loop.LoopLink(*link) for link in plan.links])
    probes = (native_loop.LoopProbe * max(1, len(plan.probes)))(
        *[native_loop.LoopProbe(*probe) for probe in plan.probes])
    failure = native_loop.LoopFailure()
    out = records[row:]
    written = dll.loop_run(fmus, order, len(plan.order), links, len(plan.links),
                           plan.signals.ctypes.data, plan.signals.shape[1], probes,
                           len(plan.probes), decimation, out.ctypes.data, t0, H, k_begin, k_end,
                           ctypes.byref(failure))
    if written < 0:
        raise plan.failure(failure.step, failure.fmu, failure.call, t0, H)
    return row + written


def _run_python(plan: _Plan, records: np.ndarray, row: int, t0: float, H: float, k_begin: int,
                k_end: int, decimation: int, hook: StepHook | None = None) -> int:
    """The same loop as native/master_loop.c in plain Python; ``hook`` (user dynamics)
    is called just before its FMU's doStep, after that FMU's links are set.

    Calls are batched (one fmi2GetReal per source FMU and one fmi2SetReal per
    target FMU and step); reads have no side effects, so the values and the
    records are the same as the native loop's, one call per link."""
    # Raw function pointers without argtypes, called with ready-made ctypes
    # arguments: ctypes then skips its per-argument conversions.
    components = [ctypes.c_void_p(f.component) for f in plan.fmus]
    do_step = [f.raw_function("fmi2DoStep") for f in plan.fmus]
    get_real = [f.raw_function("fmi2GetReal") for f in plan.fmus]
    set_real = [f.raw_function("fmi2SetReal") for f in plan.fmus]
    c_double, no = ctypes.c_double, ctypes.c_int(0)
    step = c_double(H)
    signals = plan.signals.tolist()
    steps = []  # per FMU in step order: its reads, its set, its doStep
    for f in plan.order:
        # links grouped by source FMU, so that each group's values are
        # contiguous in `values` and fmi2GetReal writes them in place
        links = sorted((l for l in plan.links if l[4] == f), key=lambda l: (l[0] < 0, l[0]))
        values = (ctypes.c_double * max(1, len(links)))()
        reads = []  # (source fmu, vr array, n, view into values)
        start = 0
        for source in sorted({l[0] for l in links if l[0] >= 0}):
            group = [l for l in links if l[0] == source]
            vrs = (ctypes.c_uint * len(group))(*[l[1] for l in group])
            view = (ctypes.c_double * len(group)).from_buffer(values, start * 8)
            reads.append((source, vrs, ctypes.c_size_t(len(group)), view))
            start += len(group)
        from_signals = [(i, l[2]) for i, l in enumerate(links) if l[0] < 0]
        noises = [(i, l[3]) for i, l in enumerate(links) if l[3] >= 0]
        targets = (ctypes.c_uint * max(1, len(links)))(*[l[5] for l in links])
        steps.append((f, reads, from_signals, noises, targets, ctypes.c_size_t(len(links)),
                      values))
    probe_vrs = [(fmu, (ctypes.c_uint * 1)(vr)) for fmu, vr in plan.probes]
    probe_value = (ctypes.c_double * 1)()
    one = ctypes.c_size_t(1)
    hook_fmu = plan.index[hook.observer_name] if hook is not None else -1
    for k in range(k_begin, k_end):
        t = t0 + k * H
        for f, reads, from_signals, noises, targets, n, values in steps:
            for source, vrs, count, view in reads:
                if get_real[source](components[source], vrs, count, view) >= 3:
                    raise plan.failure(k, source, 1, t0, H)
            for i, signal in from_signals:
                values[i] = signals[signal][k]
            for i, noise in noises:
                values[i] = values[i] + signals[noise][k]
            if n.value and set_real[f](components[f], targets, n, values) >= 3:
                raise plan.failure(k, f, 2, t0, H)
            if f == hook_fmu and hook is not None:
                hook(k, t)
            if do_step[f](components[f], c_double(t), step, no) >= 3:
                raise plan.failure(k, f, 0, t0, H)
        if (k + 1) % decimation == 0:
            out = records[row]
            out[0] = t0 + (k + 1) * H
            for p, (fmu, vr) in enumerate(probe_vrs):
                if get_real[fmu](components[fmu], vr, one, probe_value) >= 3:
                    raise plan.failure(k, fmu, 1, t0, H)
                out[p + 1] = probe_value[0]
            row += 1
    return row


def run(sim: CoSimulation, start_time: float, stop_time: float, step: float, probes: Sequence[str],
        *, decimation: int = 1, signals: Mapping[str, np.ndarray] | None = None,
        use_native: bool | None = None,
        progress: Callable[[float], None] | None = None,
        dynamics: AttachedDynamics | None = None) -> Records:
    """Run the initialized co-simulation from start_time to stop_time.

    ``signals`` are sampled at t_k = start_time + k*step, k = 0 .. n_steps-1.
    ``use_native``: True forces the native loop, False the Python loop, None
    picks native when it can be compiled.  ``progress`` receives the fraction done.
    ``dynamics``: user dynamics computing the observer's F and phi at each step
    (harness.user_dynamics); they run in the Python loop only.
    """
    if not step > 0:
        raise ValueError(f"communication step {step} must be > 0")
    if decimation < 1:
        raise ValueError(f"decimation {decimation} must be >= 1")
    n_steps = int(round((stop_time - start_time) / step))
    signals = dict(signals or {})
    plan = _Plan(sim, probes, signals, n_steps)
    records = np.empty((n_steps // decimation + 1, len(plan.probes) + 1))
    records[0, 0] = start_time
    for p, probe in enumerate(probes):
        fmu, variable = sim._split(probe)
        records[0, p + 1] = float(sim.fmus[fmu].get([variable])[0])

    hook = StepHook(sim, dynamics, signals) if dynamics is not None else None
    if hook is not None and use_native:
        raise ValueError("user dynamics run in the Python loop only: use_native must be "
                         "None or False")
    runner: Callable[..., int] = (_run_python if hook is None
                                  else partial(_run_python, hook=hook))
    if hook is None and (use_native is None or use_native):
        try:
            native_loop.load()
            runner = _run_native
        except native_loop.NativeUnavailable as error:
            if use_native:
                raise
            print(f"harness: native loop unavailable, using the Python loop ({error})",
                  file=sys.stderr)
    chunk = max(decimation, (20000 if runner is _run_native else 2000) // decimation * decimation)
    row, k = 1, 0
    while k < n_steps:
        k_next = min(n_steps, k + chunk)
        row = runner(plan, records, row, start_time, step, k, k_next, decimation)
        k = k_next
        if progress:
            progress(k / n_steps)
    return Records(records[:row, 0].copy(),
                   {name: records[:row, p + 1].copy() for p, name in enumerate(probes)})


class Progress:
    """A progress bar on stderr (tqdm) for one run, called with the fraction done.

    Shown only after the first second, and only on a terminal unless ``quiet`` is
    False explicitly (``quiet=None``: tqdm's choice, off when stderr is a file or pipe)."""

    def __init__(self, label: str, quiet: bool | None = None):
        from tqdm import tqdm

        self.bar = tqdm(total=100, desc=f"  {label}", unit="%", delay=1.0, leave=False,
                        disable=None if quiet is None else quiet,
                        bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining}")

    def __call__(self, fraction: float) -> None:
        self.bar.update(round(100 * fraction) - self.bar.n)
        if fraction >= 1.0:
            self.bar.close()
