"""User dynamics in the master loop: the observer FMU's external model computed in Python.

With ``nominal_model = 2`` the SuperTwistingObserver FMU takes the nominal
acceleration F (inputs ``F[1..n]``) and the regressor phi (inputs ``phi[1..l]``)
from its importer, so that any mechanical system M(q) q'' + C q' + P + G = u
(a closed chain, a flexible joint, coupled masses: what a URDF of a serial
chain cannot describe) is observed and identified without recompiling.

:class:`AttachedDynamics` attaches a function of the user's to the master
loop (``harness.master.run(..., dynamics=...)``).  At each communication step
k (t = t0 + k H), after the observer's links have set its inputs and just
before its doStep(t, H), the loop calls ``function(t, y, x2_hat, u)`` with

* ``y``: the observer's inputs ``y[1..n]`` as just set (the measured positions at t),
* ``x2_hat``: its outputs ``x2_hat[1..n]`` (the velocity estimate at t),
* ``u``: the values of ``inputs`` now ("fmu.variable" outputs or "signal:name" samples k),

and writes the returned F (n values) and phi (l values) to the observer, so
that its step integrates x2_hat' = F + thetabar phi + injection over [t, t + H]
with the samples of time t, as the paper's scheme (12) does.
"""
from __future__ import annotations

import ctypes
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

from .fmus import FMUError

if TYPE_CHECKING:
    from .fmus import FMUInstance
    from .master import CoSimulation

EXTERNAL_MODEL = 2  # the observer's nominal_model for F and phi as inputs


class UserDynamics(Protocol):
    """``(t, y, x2_hat, u) -> (F, phi)``: arrays of n, n and len(inputs) values in,
    sequences of n and l floats out (phi empty when l = 0)."""

    def __call__(self, t: float, y: np.ndarray, x2_hat: np.ndarray,
                 u: np.ndarray) -> tuple[Sequence[float], Sequence[float]]: ...


@dataclass(frozen=True)
class AttachedDynamics:
    """User dynamics for the observer FMU named ``observer`` (n DOF, l regressors):
    ``inputs`` name the sources of u, "fmu.variable" or "signal:name"."""

    function: UserDynamics
    n: int
    l: int
    inputs: Sequence[str] = ()
    observer: str = "observer"


class StepHook:
    """The attached dynamics bound to one co-simulation: ``hook(k, t)`` reads the
    observer's y and x2_hat and the inputs u, calls the function, sets F and phi."""

    def __init__(self, sim: CoSimulation, dynamics: AttachedDynamics,
                 signals: Mapping[str, np.ndarray]):
        self.dynamics, self.observer_name = dynamics, dynamics.observer
        if dynamics.observer not in sim.fmus:
            raise ValueError(f"user dynamics: no FMU named {dynamics.observer!r} "
                             f"(FMUs: {list(sim.fmus)})")
        observer = sim.fmus[dynamics.observer]
        self._check_observer(observer, dynamics)
        n, l = dynamics.n, dynamics.l
        vrs = [observer.vr(f"y[{i}]") for i in range(1, n + 1)] + \
              [observer.vr(f"x2_hat[{i}]") for i in range(1, n + 1)]
        self._read_vrs = (ctypes.c_uint * len(vrs))(*vrs)
        self._read = (ctypes.c_double * len(vrs))()
        writes = [observer.vr(f"F[{i}]") for i in range(1, n + 1)] + \
                 [observer.vr(f"phi[{k}]") for k in range(1, l + 1)]
        self._write_vrs = (ctypes.c_uint * len(writes))(*writes)
        self._write = (ctypes.c_double * len(writes))()
        self._observer = observer
        self._component = ctypes.c_void_p(observer.component)
        self._get = observer.raw_function("fmi2GetReal")
        self._set = observer.raw_function("fmi2SetReal")
        self._sources: list[tuple[np.ndarray | None, FMUInstance | None, int]] = []
        # (signal samples or None, fmu, vr)
        for source in dynamics.inputs:
            if source.startswith("signal:"):
                name = source[len("signal:"):]
                if name not in signals:
                    raise ValueError(f"user dynamics input from unknown signal {name!r}")
                self._sources.append((np.asarray(signals[name], dtype=float), None, 0))
            else:
                fmu, variable = sim._split(source)
                self._sources.append((None, sim.fmus[fmu], sim.fmus[fmu].vr(variable)))
        self._value = (ctypes.c_double * 1)()
        self._one_vr = (ctypes.c_uint * 1)()

    @staticmethod
    def _check_observer(observer, dynamics: AttachedDynamics) -> None:
        if dynamics.n < 1 or dynamics.l < 0:
            raise ValueError(f"user dynamics: n = {dynamics.n} must be >= 1 and "
                             f"l = {dynamics.l} >= 0")
        for name in [f"F[{dynamics.n}]"] + ([f"phi[{dynamics.l}]"] if dynamics.l else []):
            if name not in observer.variables:
                raise ValueError(f"user dynamics: {observer.name} has no input {name} "
                                 f"(n = {dynamics.n}, l = {dynamics.l} too large)")
        model, n, l = observer.get(["nominal_model", "n", "l"])
        if model != EXTERNAL_MODEL:
            raise ValueError(f"user dynamics: {observer.name} has nominal_model = {model}; "
                             f"F and phi are used only with nominal_model = {EXTERNAL_MODEL}")
        if (n, l) != (dynamics.n, dynamics.l):
            raise ValueError(f"user dynamics for n = {dynamics.n}, l = {dynamics.l}, but "
                             f"{observer.name} is set up with n = {n}, l = {l}")

    def _fail(self, what: str, t: float) -> FMUError:
        return FMUError(self._observer.describe_failure(f"{what} for the user dynamics at "
                                                        f"t = {t:.6g} s"))

    def _inputs(self, k: int, t: float) -> np.ndarray:
        u = np.empty(len(self._sources))
        for i, (samples, fmu, vr) in enumerate(self._sources):
            if samples is not None:
                u[i] = samples[k]
                continue
            assert fmu is not None  # a source is a signal or an FMU's variable
            self._one_vr[0] = vr
            if fmu.raw_function("fmi2GetReal")(ctypes.c_void_p(fmu.component), self._one_vr,
                                               ctypes.c_size_t(1), self._value) >= 3:
                raise FMUError(fmu.describe_failure(f"fmi2GetReal for the user dynamics at "
                                                    f"t = {t:.6g} s"))
            u[i] = self._value[0]
        return u

    def __call__(self, k: int, t: float) -> None:
        n, l = self.dynamics.n, self.dynamics.l
        if self._get(self._component, self._read_vrs, ctypes.c_size_t(2 * n), self._read) >= 3:
            raise self._fail("fmi2GetReal", t)
        state = np.ctypeslib.as_array(self._read).copy()
        F, phi = self.dynamics.function(t, state[:n], state[n:], self._inputs(k, t))
        values = np.concatenate([np.asarray(F, dtype=float).ravel(),
                                 np.asarray(phi, dtype=float).ravel()])
        if values.size != n + l or np.size(F) != n:
            raise ValueError(f"user dynamics at t = {t:.6g} s returned {np.size(F)} values of F "
                             f"and {np.size(phi)} of phi; the observer takes n = {n} and l = {l}")
        bad = [i for i, v in enumerate(values) if not math.isfinite(v)]
        if bad:
            i = bad[0]
            name = f"F[{i + 1}]" if i < n else f"phi[{i - n + 1}]"
            raise ValueError(f"user dynamics at t = {t:.6g} s returned {name} = {values[i]}, "
                             f"not finite")
        self._write[:] = values.tolist()
        if self._set(self._component, self._write_vrs, ctypes.c_size_t(n + l), self._write) >= 3:
            raise self._fail("fmi2SetReal", t)
