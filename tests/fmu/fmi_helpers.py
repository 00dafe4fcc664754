"""Raw FMI 2.0 and FMI 3.0 access to a built FMU for the FMI-behaviour tests: a
logger that records messages, status codes instead of exceptions, and NULL pointers."""
from __future__ import annotations

import ctypes
import os
from pathlib import Path

import numpy as np
from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)

OK, WARNING, DISCARD, ERROR = 0, 1, 2, 3


def instances(raw_class, fmu: Path):
    """A pytest fixture body: yields a factory of ``raw_class`` (RawFMU or RawFMU3)
    instances of ``fmu`` and frees every one it made when the test ends."""
    made = []

    def factory(name: str = "instance", instantiate: bool = True):
        instance = raw_class(fmu, name, instantiate=instantiate)
        made.append(instance)
        return instance

    yield factory
    for instance in made:
        instance.free()


class RawFMU:
    """One instance; ``call(name, *args)`` returns the fmi2Status, ``log`` holds messages."""

    _extracted: dict[Path, str] = {}

    def __init__(self, fmu: Path, name: str = "instance", instantiate: bool = True):
        self.md = read_model_description(str(fmu))
        if fmu not in RawFMU._extracted:
            RawFMU._extracted[fmu] = extract(str(fmu))
        self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=RawFMU._extracted[fmu],
                               modelIdentifier=self.md.coSimulation.modelIdentifier,
                               instanceName=name)
        self.f = self.slave._functions
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.log: list[tuple[int, str]] = []
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self.c = None
        if instantiate:
            self.instantiate(name)

    def _log(self, env, instance, status, category, message):
        self.log.append((status, message.decode() if message else ""))

    def instantiate(self, name="instance", guid=None, callbacks="default"):
        cb = self.callbacks if callbacks == "default" else callbacks
        self.c = self.f["fmi2Instantiate"](name.encode() if name is not None else None, 1,
                                           (guid or self.md.guid).encode(), b"file:///tmp",
                                           ctypes.byref(cb) if cb is not None else None, 0, 0)
        return self.c

    def call(self, function: str, *args) -> int:
        return self.f[function](self.c, *args)

    def messages(self) -> str:
        return "\n".join(m for _, m in self.log)

    # typed helpers ---------------------------------------------------------
    def set_real(self, values: dict[str, float]) -> int:
        vrs = (ctypes.c_uint * len(values))(*[self.vr[n] for n in values])
        vals = (ctypes.c_double * len(values))(*values.values())
        return self.call("fmi2SetReal", vrs, len(values), vals)

    def set_integer(self, values: dict[str, int]) -> int:
        vrs = (ctypes.c_uint * len(values))(*[self.vr[n] for n in values])
        vals = (ctypes.c_int * len(values))(*values.values())
        return self.call("fmi2SetInteger", vrs, len(values), vals)

    def set_boolean(self, values: dict[str, bool]) -> int:
        vrs = (ctypes.c_uint * len(values))(*[self.vr[n] for n in values])
        vals = (ctypes.c_int * len(values))(*[int(v) for v in values.values()])
        return self.call("fmi2SetBoolean", vrs, len(values), vals)

    def get_real(self, names: list[str]) -> list[float]:
        vrs = (ctypes.c_uint * len(names))(*[self.vr[n] for n in names])
        vals = (ctypes.c_double * len(names))()
        status = self.call("fmi2GetReal", vrs, len(names), vals)
        assert status == OK, self.messages()
        return list(vals)

    def get_boolean(self, names: list[str]) -> list[bool]:
        vrs = (ctypes.c_uint * len(names))(*[self.vr[n] for n in names])
        vals = (ctypes.c_int * len(names))()
        assert self.call("fmi2GetBoolean", vrs, len(names), vals) == OK, self.messages()
        return [bool(v) for v in vals]

    def setup(self, start: float = 0.0) -> int:
        return self.call("fmi2SetupExperiment", 0, 0.0, start, 0, 0.0)

    def initialize(self, reals=None, integers=None, booleans=None, start: float = 0.0) -> int:
        """setup, parameters, enter and exit initialization mode; returns the worst status."""
        statuses = [self.setup(start)]
        if integers:
            statuses.append(self.set_integer(integers))
        if booleans:
            statuses.append(self.set_boolean(booleans))
        if reals:
            statuses.append(self.set_real(reals))
        statuses.append(self.call("fmi2EnterInitializationMode"))
        statuses.append(self.call("fmi2ExitInitializationMode"))
        return max(statuses)

    def do_step(self, t: float, h: float) -> int:
        return self.call("fmi2DoStep", t, h, 1)

    def free(self):
        if self.c:
            self.f["fmi2FreeInstance"](self.c)
            self.c = None


class RawFMU3:
    """One FMI 3.0 Co-Simulation instance with status codes instead of exceptions.

    ``call(name, *args)`` calls fmi3<name> on the instance and returns the fmi3Status;
    ``log`` holds (status, message) of everything the FMU logged; ``vr`` maps names to
    value references and ``size`` to element counts (arrays have one reference each)."""

    _extracted: dict[Path, str] = {}

    def __init__(self, fmu: Path, name: str = "instance", instantiate: bool = True):
        from fmpy.fmi3 import FMU3Slave, fmi3LogMessageCallback

        self.md = read_model_description(str(fmu))
        if fmu not in RawFMU3._extracted:
            RawFMU3._extracted[fmu] = extract(str(fmu))
        self.slave = FMU3Slave(guid=self.md.guid, unzipDirectory=RawFMU3._extracted[fmu],
                               modelIdentifier=self.md.coSimulation.modelIdentifier,
                               instanceName=name)
        self.f = self.slave._functions
        # the resource path as FMI 3 gives it: native, with a trailing separator
        self.resources = os.path.join(RawFMU3._extracted[fmu], "resources", "")
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.size = {v.name: int(np.prod(v.shape)) if v.shape else 1
                     for v in self.md.modelVariables}
        self.log: list[tuple[int, str]] = []
        self._logger = fmi3LogMessageCallback(self._log)
        self.c = None
        if instantiate:
            self.instantiate(name)

    def _log(self, env, status, category, message):
        self.log.append((status, message.decode() if message else ""))

    def instantiate(self, name="instance", token=None, event_mode=False, n_required=0):
        required = (ctypes.c_uint * max(1, n_required))()
        self.c = self.f["fmi3InstantiateCoSimulation"](
            name.encode() if name is not None else None, (token or self.md.guid).encode(),
            self.resources.encode(), False, False, event_mode, False, required, n_required, None,
            self._logger,
            self.f["fmi3InstantiateCoSimulation"].argtypes[-1]())  # no intermediate update
        return self.c

    def call(self, function: str, *args) -> int:
        return self.f["fmi3" + function](self.c, *args)

    def messages(self) -> str:
        return "\n".join(m for _, m in self.log)

    def _values(self, names, c_type, values=None):
        vrs = (ctypes.c_uint * len(names))(*[self.vr[n] for n in names])
        n = sum(self.size[name] for name in names)
        array = (c_type * n)(*(values or []))
        return vrs, array, n

    def get(self, kind: str, names: list[str]) -> list:
        """Flat list of the values of the named variables (kind: Float64, Int32, Boolean)."""
        c_type = {"Float64": ctypes.c_double, "Int32": ctypes.c_int32, "Boolean": ctypes.c_bool}
        vrs, array, n = self._values(names, c_type[kind])
        status = self.call("Get" + kind, vrs, len(names), array, n)
        assert status == OK, self.messages()
        return list(array)

    def set(self, kind: str, values: dict[str, list]) -> int:
        """Sets the named variables to flat lists of values; returns the fmi3Status."""
        c_type = {"Float64": ctypes.c_double, "Int32": ctypes.c_int32, "Boolean": ctypes.c_bool}
        flat = [x for value in values.values() for x in value]
        vrs, array, n = self._values(list(values), c_type[kind], flat)
        return self.call("Set" + kind, vrs, len(values), array, n)

    def initialize(self, start: float = 0.0, stop: float | None = None, reals=None) -> int:
        """Enter (with the experiment) and exit initialization mode; the worst status."""
        statuses = [self.call("EnterInitializationMode", False, 0.0, start, stop is not None,
                              stop or 0.0)]
        if reals:
            statuses.append(self.set("Float64", reals))
        statuses.append(self.call("ExitInitializationMode"))
        return max(statuses)

    def do_step(self, t: float, h: float) -> tuple[int, bool, bool, bool, float]:
        """(status, eventHandlingNeeded, terminateSimulation, earlyReturn, lastSuccessfulTime)"""
        flags = [ctypes.c_bool(True) for _ in range(3)]
        last = ctypes.c_double(float("nan"))
        status = self.call("DoStep", t, h, True, *(ctypes.byref(f) for f in flags),
                           ctypes.byref(last))
        return (status, *(f.value for f in flags), last.value)

    def free(self):
        if self.c:
            self.f["fmi3FreeInstance"](self.c)
            self.c = None
