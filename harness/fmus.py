"""Loading FMI 2.0 co-simulation FMUs with fmpy, with name-based, typed access.

An :class:`FMUInstance` wraps :class:`fmpy.fmi2.FMU2Slave`: it captures the
FMU's log messages (so that a failure raises an error that says what the FMU
said) and exposes the raw ctypes FMI functions that the master loops use.
"""
from __future__ import annotations

import ctypes
import logging
import shutil
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from functools import partial
from pathlib import Path

from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)

from .tempdirs import owned_temp_dir
from .values import BadValue, fmi_value

Value = float | int | bool

STATUS_NAMES = ("OK", "Warning", "Discard", "Error", "Fatal", "Pending")
# FMI status -> logging level of the FMU's log lines (logger "harness.fmu")
STATUS_LEVELS = (logging.DEBUG, logging.WARNING, logging.WARNING, logging.ERROR,
                 logging.CRITICAL, logging.INFO)
LOGGER = logging.getLogger("harness.fmu")
MAX_REPEATS = 5  # the same line is passed on this many times per instance, then counted



def _address(pointer: ctypes.c_void_p) -> int:
    """The address a pointer holds; a NULL one is a broken instance, never 0 handed on."""
    if pointer.value is None:
        raise RuntimeError("a NULL FMI function or component pointer")
    return pointer.value

class FMUError(RuntimeError):
    """An FMI call failed; the message includes what the FMU logged."""


@dataclass(frozen=True)
class Variable:
    name: str
    value_reference: int
    type: str  # "Real", "Integer" or "Boolean"
    causality: str
    min: float | None = None  # the declared range (None: unbounded)
    max: float | None = None


def _bound(text: str | None) -> float | None:
    return None if text in (None, "") else float(text)


def variables_of(model_description) -> dict[str, Variable]:
    """name -> Variable of an fmpy model description."""
    return {v.name: Variable(v.name, v.valueReference, v.type, v.causality, _bound(v.min),
                             _bound(v.max))
            for v in model_description.modelVariables}


def check_value(variable: Variable, value: object, where: str = "") -> Value:
    """``value`` converted to ``variable``'s type; FMUError (prefixed by ``where``)
    if it is not one: an Integer must be integral and in its declared range (never
    wrapped to 32 bits or truncated), a Boolean true/false or 1/0, a Real finite
    (the FMU checks a Real's range itself, open ends included)."""
    try:
        if variable.type == "Integer":
            return fmi_value(variable.name, "Integer", value, variable.min, variable.max)
        return fmi_value(variable.name, variable.type, value)
    except BadValue as error:
        raise FMUError(f"{where}{error}") from None


def check_parameters(fmu: str | Path, values: Mapping[str, object]) -> dict[str, Value]:
    """Checks values for an FMU's parameters and inputs before it is instantiated:
    each name must be a variable that can be set, each value fit its type and
    range (check_value).  Returns the typed values; FMUError names the problem."""
    variables = variables_of(read_model_description(str(fmu)))
    out: dict[str, Value] = {}
    for name, value in values.items():
        if name not in variables:
            raise FMUError(f"{Path(fmu).name} has no variable named {name!r}")
        variable = variables[name]
        if variable.causality not in ("parameter", "input"):
            kind = {"calculatedParameter": "a calculated parameter", "output": "an output",
                    "local": "a local variable"}.get(variable.causality, variable.causality)
            raise FMUError(f"{name} is {kind} of {Path(fmu).name}: it cannot be set")
        out[name] = check_value(variable, value)
    return out


class FMUInstance:
    """One instantiated co-simulation FMU.

    Parameters are set by name with :meth:`set`; :meth:`initialize` runs
    setupExperiment / enterInitializationMode / exitInitializationMode.
    """

    def __init__(self, fmu: str | Path, instance_name: str, *, debug_logging: bool = False):
        self.path = Path(fmu)
        self.name = instance_name
        self.model_description = read_model_description(str(self.path))
        if self.model_description.coSimulation is None:
            raise FMUError(f"{self.path}: not a co-simulation FMU")
        # named after this process: tempdirs.remove_stale clears it if the process is killed
        self._unzip_dir = extract(str(self.path), unzipdir=str(owned_temp_dir("fmu")))
        self.variables = variables_of(self.model_description)
        self.messages: list[str] = []
        self._repeats: dict[str, int] = {}
        self.failed = False  # an FMI call failed: terminate is not allowed any more
        self._callbacks = self._make_callbacks()
        self.slave = FMU2Slave(
            guid=self.model_description.guid,
            unzipDirectory=self._unzip_dir,
            modelIdentifier=self.model_description.coSimulation.modelIdentifier,
            instanceName=instance_name,
        )
        self._call(lambda: self.slave.instantiate(callbacks=self._callbacks,
                                                  loggingOn=debug_logging), "instantiate")
        functions = self.slave._functions  # the raw ctypes functions fmpy loaded
        self.fmi2DoStep = functions["fmi2DoStep"]
        self.fmi2GetReal = functions["fmi2GetReal"]
        self.fmi2SetReal = functions["fmi2SetReal"]

    # -- logging -------------------------------------------------------------
    def _make_callbacks(self) -> fmi2CallbackFunctions:
        def log(_env, instance_name, status, category, message):
            # the FMU escapes '%' and '#' for printf-style loggers: show the text
            text = (message.decode(errors="replace") if message else "") \
                .replace("%%", "%").replace("##", "#")
            label = STATUS_NAMES[status] if 0 <= status < len(STATUS_NAMES) else str(status)
            self.messages.append(f"[{label}] {text}")
            self._forward(status, text)

        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(log)
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        return callbacks

    def _forward(self, status: int, text: str) -> None:
        """Passes a log line to the logging module (logger ``harness.fmu``): Warning and
        Discard as WARNING, Error as ERROR, Fatal as CRITICAL, OK as DEBUG."""
        level = STATUS_LEVELS[status] if 0 <= status < len(STATUS_LEVELS) else logging.ERROR
        seen = self._repeats.get(text, 0) + 1
        self._repeats[text] = seen
        if seen <= MAX_REPEATS:
            suffix = " (further identical lines not shown)" if seen == MAX_REPEATS else ""
            LOGGER.log(level, "%s (%s): %s%s", self.name, self.path.name, text, suffix)

    def _call(self, action, what: str):
        before = len(self.messages)
        try:
            return action()
        except FMICallException as error:
            self.failed = True
            said = "; ".join(self.messages[before:]) or "(the FMU logged nothing)"
            raise FMUError(f"{self.name}: {what} failed: {said}") from error

    def warnings(self) -> list[str]:
        """Log lines of status Warning or worse received so far."""
        return [m for m in self.messages if not m.startswith("[OK]")]

    # -- variables -------------------------------------------------------------
    def variable(self, name: str) -> Variable:
        try:
            return self.variables[name]
        except KeyError:
            raise KeyError(f"{self.name}: no variable named {name!r} in "
                           f"{self.path.name}") from None

    def vr(self, name: str) -> int:
        return self.variable(name).value_reference

    def set(self, values: Mapping[str, Value]) -> None:
        """Set variables by name, converting each value to the variable's type
        (checked first: see :func:`check_value`)."""
        for name, value in values.items():
            var = self.variable(name)
            typed = check_value(var, value, f"{self.name}: ")
            setter = {"Real": self.slave.setReal, "Integer": self.slave.setInteger,
                      "Boolean": self.slave.setBoolean}[var.type]
            self._call(partial(setter, [var.value_reference], [typed]),
                       f"setting {name} = {value!r}")

    def get(self, names: Iterable[str]) -> list[Value]:
        """Get variables by name (any type)."""
        out: list[Value] = []
        for name in names:
            var = self.variable(name)
            getter = {"Real": self.slave.getReal, "Integer": self.slave.getInteger,
                      "Boolean": self.slave.getBoolean}[var.type]
            out.append(self._call(partial(getter, [var.value_reference]), f"getting {name}")[0])
        return out

    # -- lifecycle -------------------------------------------------------------
    def setup(self, start_time: float, parameters: Mapping[str, Value]) -> None:
        """setupExperiment, parameters, enterInitializationMode (inputs may follow)."""
        self._call(lambda: self.slave.setupExperiment(startTime=start_time), "setupExperiment")
        self.set(parameters)
        self._call(self.slave.enterInitializationMode, "enterInitializationMode")

    def reset(self) -> None:
        """fmi2Reset: back to the freshly instantiated state; forgets the log."""
        self._call(self.slave.reset, "fmi2Reset")
        self.messages.clear()
        self._repeats.clear()
        self.failed = False

    def exit_initialization(self) -> None:
        self._call(self.slave.exitInitializationMode, "exitInitializationMode")

    def do_step(self, t: float, step: float) -> None:
        self._call(lambda: self.slave.doStep(t, step), f"doStep at t = {t}")

    def describe_failure(self, what: str) -> str:
        said = "; ".join(self.warnings()[-3:]) or "(the FMU logged nothing)"
        return f"{self.name}: {what}: {said}"

    def close(self) -> None:
        """Terminate (when possible) and free the instance; remove the extracted files."""
        if self.slave is not None:
            if not self.failed:
                try:
                    self.slave.terminate()
                except FMICallException:
                    pass
            self.slave.freeInstance()
            self.slave = None
        shutil.rmtree(self._unzip_dir, ignore_errors=True)

    def __enter__(self) -> FMUInstance:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- raw handles for the native loop ----------------------------------------
    def function_address(self, name: str) -> int:
        return _address(ctypes.cast(self.slave._functions[name], ctypes.c_void_p))

    def raw_function(self, name: str):
        """The FMI function without ctypes argument types (the caller passes ctypes
        objects); cached per instance.  The library stays loaded while it is held."""
        if not hasattr(self, "_raw_library"):
            self._raw_library = ctypes.CDLL(self.slave.dll._name)
        return getattr(self._raw_library, name)

    @property
    def component(self) -> int:
        return _address(ctypes.cast(self.slave.component, ctypes.c_void_p))
