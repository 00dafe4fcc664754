"""Raw FMI 2.0 access to a built FMU for the FMI-behaviour tests: a logger that
records messages, status codes instead of exceptions, and NULL pointers."""
from __future__ import annotations

import ctypes
from pathlib import Path

from fmpy import extract, read_model_description
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy import calloc, free

OK, WARNING, DISCARD, ERROR = 0, 1, 2, 3


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
