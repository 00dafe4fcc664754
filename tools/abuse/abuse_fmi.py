"""Raw FMI 2.0 access for the abuse tests and the fuzzers' seed corpus (make_corpus.py): any FMU,
any pointer, any call order.

The FMUs come from $STO_FMU_DIR (tools/abuse/sanitize.sh points it at the
sanitized build) or build/fmus.  ``isolated(fn)`` runs ``fn`` in a forked
child so that a crash (a signal, or a sanitizer's abort) fails one test
instead of killing pytest.
"""
from __future__ import annotations

import ctypes
import os
import pickle
import select
import signal
import struct
import time
import traceback
from pathlib import Path

from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.model_description import ModelDescription

from tools.abuse import state_format
from tools.fmu_models import models

REPO = Path(__file__).resolve().parents[2]
OK, WARNING, DISCARD, ERROR, FATAL = 0, 1, 2, 3, 4
MODELS = models()
CO_SIMULATION, MODEL_EXCHANGE = 1, 0


def fmu_dir() -> Path:
    return Path(os.environ.get("STO_FMU_DIR", REPO / "build" / "fmus")).resolve()


def fmu_path(model: str) -> Path:
    path = fmu_dir() / f"{model}.fmu"
    if not path.exists():
        raise FileNotFoundError(f"{path} is missing: run ./build.sh fmus "
                                "(or tools/abuse/sanitize.sh for the sanitized FMUs)")
    return path


_extracted: dict[Path, str] = {}
_descriptions: dict[Path, ModelDescription] = {}


def unzipped(model: str) -> tuple[ModelDescription, str]:
    path = fmu_path(model)
    if path not in _extracted:
        _descriptions[path] = read_model_description(str(path))
        _extracted[path] = extract(str(path))
    return _descriptions[path], _extracted[path]


def fmi_unescape(message: str) -> tuple[str, str | None]:
    """The text an FMI 2 logger shows for ``message``, which it reads as a printf
    format in which "#<type><vr>#" names a variable (FMI 2.0 section 2.1.5):
    "%%" is "%", "##" is "#".  Returns (text, problem): problem says where the
    message has a lone '%' (a conversion: a printf-style logger reads arguments
    that are not there, and crashes) or a lone '#' (a variable reference, which
    this project's FMUs never write), else None."""
    out: list[str] = []
    i = 0
    while i < len(message):
        c = message[i]
        if c in "%#":
            if message[i + 1:i + 2] != c:
                return "".join(out), f"lone {c!r} at {i} in {message!r}"
            i += 1
        out.append(c)
        i += 1
    return "".join(out), None


class Callbacks:
    """An fmi2CallbackFunctions whose logger records (status, category, text).

    The text is the message as an FMI logger shows it (fmi_unescape); a
    message that is not escaped for the logger goes to ``escaping_errors``."""

    def __init__(self, logger: bool = True, memory: bool = True) -> None:
        self.log: list[tuple[int, str, str]] = []
        self.escaping_errors: list[str] = []
        self.struct = fmi2CallbackFunctions()
        # keep the thunks alive as long as this object
        self._logger = fmi2CallbackLoggerTYPE(self._record) if logger else None
        if logger:
            self.struct.logger = self._logger
        if memory:
            self._allocate = fmi2CallbackAllocateMemoryTYPE(calloc)
            self._free = fmi2CallbackFreeMemoryTYPE(free)
            self.struct.allocateMemory = self._allocate
            self.struct.freeMemory = self._free

    def _record(self, env, instance, status, category, message):
        text, problem = fmi_unescape((message or b"").decode("utf-8", errors="replace"))
        if problem:
            self.escaping_errors.append(problem)
        self.log.append((status, (category or b"").decode(), text))


class Raw:
    """One FMU's raw fmi2 functions and (optionally) one instance of it."""

    def __init__(self, model: str, name: str = "abuse", instantiate: bool = True,
                 callbacks: Callbacks | None = None):
        self.model = model
        self.md, directory = unzipped(model)
        self.guid = self.md.guid
        self.resources = (Path(directory) / "resources").as_uri().encode()
        # the FMU reads a file of its resources at instantiation (ModelObserver)
        self.reads_resources = any((Path(directory) / "resources").glob("*"))
        self.slave = FMU2Slave(guid=self.guid, unzipDirectory=directory,
                               modelIdentifier=self.md.coSimulation.modelIdentifier,
                               instanceName=name)
        self.f = self.slave._functions
        self.variables = {v.name: v for v in self.md.modelVariables}
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.cb = callbacks or Callbacks()
        self.c = None
        if instantiate:
            self.c = self.instantiate(name)
            assert self.c, self.messages()

    # -- instance --------------------------------------------------------------------------
    def instantiate(self, name="abuse", fmu_type=CO_SIMULATION, guid="default",
                    resources=b"default", callbacks="default"):
        cb = self.cb if callbacks == "default" else callbacks
        resources = self.resources if resources == b"default" else resources
        guid = self.guid.encode() if guid == "default" else guid
        name = name.encode() if isinstance(name, str) else name
        pointer = ctypes.byref(cb.struct) if cb is not None else None
        return self.f["fmi2Instantiate"](name, fmu_type, guid, resources, pointer, 0, 0)

    def call(self, function: str, *args) -> int:
        return self.f[function](self.c, *args)

    def free(self):
        if self.c:
            self.f["fmi2FreeInstance"](self.c)
            self.c = None

    def errors(self) -> str:
        """The messages logged with status Error or worse."""
        return "\n".join(m for s, _, m in self.cb.log if s >= ERROR)

    def messages(self) -> str:
        return "\n".join(m for _, _, m in self.cb.log)

    def clear_log(self):
        self.cb.log.clear()

    def assert_escaped(self):
        """Every message logged so far was escaped for the FMI logger."""
        assert not self.cb.escaping_errors, self.cb.escaping_errors[:3]

    # -- typed access ----------------------------------------------------------------------
    def vrs(self, names) -> ctypes.Array:
        return (ctypes.c_uint * len(names))(*[self.vr[n] if isinstance(n, str) else n
                                              for n in names])

    def set_real(self, values: dict) -> int:
        return self.call("fmi2SetReal", self.vrs(list(values)), len(values),
                         (ctypes.c_double * len(values))(*values.values()))

    def set_integer(self, values: dict) -> int:
        return self.call("fmi2SetInteger", self.vrs(list(values)), len(values),
                         (ctypes.c_int * len(values))(*values.values()))

    def set_boolean(self, values: dict) -> int:
        return self.call("fmi2SetBoolean", self.vrs(list(values)), len(values),
                         (ctypes.c_int * len(values))(*[int(v) for v in values.values()]))

    def set(self, values: dict) -> int:
        """Sets each value with the function of its variable's type; worst status."""
        worst = OK
        for name, value in values.items():
            kind = self.variables[name].type
            setter = {"Real": self.set_real, "Integer": self.set_integer,
                      "Boolean": self.set_boolean}[kind]
            worst = max(worst, setter({name: value}))
        return worst

    def get_real(self, names) -> tuple[int, list[float]]:
        values = (ctypes.c_double * len(names))()
        status = self.call("fmi2GetReal", self.vrs(names), len(names), values)
        return status, list(values)

    def setup(self, start=0.0, stop=None) -> int:
        return self.call("fmi2SetupExperiment", 0, 0.0, start, int(stop is not None),
                         0.0 if stop is None else stop)

    def initialize(self, parameters: dict | None = None, start=0.0, stop=None) -> int:
        statuses = [self.setup(start, stop)]
        if parameters:
            statuses.append(self.set(parameters))
        statuses.append(self.call("fmi2EnterInitializationMode"))
        statuses.append(self.call("fmi2ExitInitializationMode"))
        return max(statuses)

    def do_step(self, t: float, H: float) -> int:
        return self.call("fmi2DoStep", t, H, 1)

    # -- FMU state -------------------------------------------------------------------------
    def get_state(self) -> ctypes.c_void_p:
        state = ctypes.c_void_p()
        assert self.call("fmi2GetFMUstate", ctypes.byref(state)) == OK, self.messages()
        return state

    def serialize(self, state) -> bytes:
        size = ctypes.c_size_t()
        assert self.call("fmi2SerializedFMUstateSize", state, ctypes.byref(size)) == OK
        buffer = (ctypes.c_char * size.value)()
        assert self.call("fmi2SerializeFMUstate", state, buffer, size.value) == OK
        return buffer.raw

    def deserialize(self, data: bytes, state: ctypes.c_void_p | None = None):
        state = state if state is not None else ctypes.c_void_p()
        buffer = (ctypes.c_char * max(1, len(data))).from_buffer_copy(data or b"\0")
        status = self.call("fmi2DeSerializeFMUstate", buffer, len(data), ctypes.byref(state))
        return status, state


# ---- a normal life: what every FMU must still do after the abuse -------------------------------

NORMAL_STEP = 1e-3  # a multiple of every FMU's default internal step


def normal_run(fmu: Raw, steps: int = 5) -> list[int]:
    """setup, init and a few steps with valid values; the statuses of every call."""
    statuses = [fmu.initialize()]
    for k in range(steps):
        statuses.append(fmu.do_step(k * NORMAL_STEP, NORMAL_STEP))
    return statuses


def assert_usable_after_reset(fmu: Raw):
    assert fmu.call("fmi2Reset") == OK, fmu.messages()
    statuses = normal_run(fmu)
    assert statuses == [OK] * len(statuses), (statuses, fmu.messages())


# ---- serialized states ---------------------------------------------------------------------

# fmu/src/instance/state_format.h: a header, the clock, then the model data
HEADER_SIZE = state_format.header_size()
CLOCK_SIZE = state_format.clock_size()


def forge(serialized: bytes) -> bytes:
    """The same bytes with a checksum that matches them: what anyone can compute."""
    data = bytearray(serialized)
    struct.pack_into("<Q", data, state_format.offset("checksum"), state_format.checksum(serialized))
    return bytes(data)


def parameter_offset(model: str, name: str, a, b, size: int) -> int:
    """Offset in a serialized state of the ``size``-byte field behind parameter
    ``name``, found by diffing the states of two fresh instances that differ
    only in that parameter (``a`` and ``b``)."""
    states = []
    for value in (a, b):
        fmu = Raw(model, "probe")
        assert fmu.set({name: value}) == OK, fmu.messages()
        state = fmu.get_state()
        states.append(fmu.serialize(state))
        fmu.call("fmi2FreeFMUstate", ctypes.byref(state))
        fmu.free()
    diff = [i for i, (x, y) in enumerate(zip(*states)) if x != y and i >= HEADER_SIZE + CLOCK_SIZE]
    assert diff, f"{name}: no difference between the states"
    return diff[0] - (diff[0] - HEADER_SIZE) % size


# ---- crash isolation -----------------------------------------------------------------------

def isolated(fn, *args, timeout: float = 120.0):
    """Runs fn(*args) in a forked child.  Its exceptions come back as an
    AssertionError with the child's traceback; a child killed by a signal,
    exiting without a report (a sanitizer abort) or running past ``timeout``
    seconds fails with what happened."""
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:  # child
        os.close(read_end)
        code = 0
        try:
            fn(*args)
            report = None
        except BaseException:  # noqa: BLE001 - everything goes back to the parent
            report = traceback.format_exc()
            code = 1
        with os.fdopen(write_end, "wb") as out:
            out.write(pickle.dumps(report))
        os._exit(code)
    os.close(write_end)
    chunks, deadline = [], time.monotonic() + timeout
    with os.fdopen(read_end, "rb", buffering=0) as source:
        while True:
            ready, _, _ = select.select([source], [], [], max(0.0, deadline - time.monotonic()))
            if not ready:
                os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
                raise AssertionError(f"the call did not return within {timeout} s")
            chunk = source.read(65536)
            if not chunk:
                break
            chunks.append(chunk)
    payload = b"".join(chunks)
    _, status = os.waitpid(pid, 0)
    if os.WIFSIGNALED(status):
        raise AssertionError(f"the FMU crashed the process: signal {os.WTERMSIG(status)}")
    code = os.WEXITSTATUS(status)
    if not payload:
        raise AssertionError(f"the process died without a report (exit status {code}; "
                             "a sanitizer error is printed on stderr)")
    report = pickle.loads(payload)
    if report is not None:
        raise AssertionError(f"in the isolated process:\n{report}")
    assert code == 0, f"exit status {code}"
