"""Forged FMU states, FMI 2 and FMI 3: a serialized state patched field by field
with its checksum recomputed (the checksum is FNV-1a: anyone can recompute it).

The FMU must refuse every such state at deserialization with Error and a
message that names the field, and stay usable: the counts, indices and sizes
that the step loops trust (Observer: info.blocks.pairs, first, second;
RobotObserver: obs.n, model.n, id.run_start, id.run_end, ...) once crashed the
importer on the next step (signal 11).  States the FMU wrote itself, from every
kind of configuration, must still be accepted and continue the run exactly.
Every case runs in a forked child (abuse_fmi.isolated): a crash fails one case.
"""
from __future__ import annotations

import ctypes
import math
import os
import struct
from pathlib import Path

import pytest

from fmu.fmi_helpers import RawFMU3
from tools.abuse.abuse_fmi import ERROR, OK, REPO, Raw, assert_usable_after_reset, forge, isolated

from .state_layout import field_location

OBS, ROBOT, MODEL = "SuperTwistingObserver", "RobotObserver", "ModelObserver"
H = 1e-3
STEPS = 300  # past the robot's t_id = 0.2 s: its identifier and statistics job run
# identifier 1: LSM in information form, whose block scores hold the pair lists
SETUP = {OBS: {"identifier": 1}, ROBOT: {"f_plus[1]": 1000.0, "f_plus[2]": 1000.0},
         MODEL: {"t_id": 0.0}}
FORMAT = {"i": "<i", "u": "<I", "d": "<d"}
INT_MAX = 2**31 - 1

# (model, [(field, format, value), ...], what the refusal must name)
CASES = [
    (OBS, [("pipe.info.blocks.pairs", "i", 10**6)], "info.blocks.pairs"),
    (OBS, [("pipe.info.blocks.first[0]", "i", 10**8)], "info.blocks.first"),
    (OBS, [("pipe.info.blocks.second[0]", "i", -10**8)], "info.blocks.second"),
    (OBS, [("pipe.info.m", "i", 8), ("pipe.id.m", "i", 8)], "id.m"),
    (OBS, [("pipe.m", "i", 7)], "m in the state is not what initialization derives"),
    (OBS, [("pipe.selected[0]", "i", -5)], "selected"),
    (OBS, [("pipe.obs.n", "i", 0)], "obs.n"),
    (OBS, [("pipe.obs.implicit.reversal_age[0]", "i", INT_MAX)], "obs.implicit.reversal_age"),
    (OBS, [("pipe.obs.implicit.smooth_samples[1]", "i", -1)], "obs.implicit.smooth_samples"),
    (OBS, [("pipe.bank.center[0]", "i", 1000)], "bank.center"),
    (OBS, [("pipe.bank.follow", "i", 15)], "an index of bank"),
    (OBS, [("pipe.bank.zoom_index[0][1]", "i", 40)], "an index of bank"),
    (OBS, [("pipe.bank.stride", "i", 0)], "bank.stride"),
    (OBS, [("pipe.info.anchor_age", "i", -1)], "info.anchor_age"),
    (OBS, [("pipe.info.lambda", "d", 0.5)], "info.lambda"),
    (OBS, [("pipe.identifier_gain", "d", 1e300)], "identifier_gain"),
    (OBS, [("reset_seen", "i", 7)], "reset_seen"),
    (OBS, [("alpha1_used[0]", "d", 1e9)], "alpha1_used[1]"),
    (OBS, [("pipe.obs.x1_hat[0]", "d", math.nan)], "x1_hat[1]"),
    (OBS, [("pipe.obs.implicit.z1[0]", "d", math.inf)], "obs (its byte"),
    (OBS, [("pipe.info.P[0][0]", "d", math.nan)], "info (its byte"),
    (OBS, [("out.converged", "i", 3)], "converged"),
    (ROBOT, [("obs.n", "i", 0), ("model.n", "i", 100000)], "model"),
    (ROBOT, [("id.run_end[0][0]", "i", 100000)], "id.run_end"),
    (ROBOT, [("id.run_start[0][0]", "i", -100000)], "id.run_start"),
    (ROBOT, [("id.runs[1]", "i", 50)], "id.runs"),
    (ROBOT, [("id.p", "i", 84)], "id.p"),
    (ROBOT, [("id.columns[0]", "i", -1)], "id.columns"),
    (ROBOT, [("id.anchor_unit", "i", -3)], "id.anchor_unit"),
    (ROBOT, [("id.anchor_age", "i", INT_MAX)], "id.anchor_age"),
    (ROBOT, [("id.anchor_unit", "i", 40)], "id.anchor_unit"),
    (ROBOT, [("id.batch_age", "i", -2)], "id.batch_age"),
    (ROBOT, [("statistics.stage", "i", 9)], "statistics.stage"),
    (ROBOT, [("statistics.stage", "i", 1), ("statistics.index", "i", 60)], "statistics.index"),
    (ROBOT, [("statistics.p", "i", 84)], "statistics.p"),
    (ROBOT, [("regression.settled[0]", "i", -1)], "regression.settled"),
    (ROBOT, [("regression.margin_samples", "i", -7)], "regression.margin_samples"),
    (ROBOT, [("obs.steps", "d", -1.0)], "obs.steps"),
    (ROBOT, [("obs.dof[0].z1", "d", math.nan)], "obs (its byte"),
    (ROBOT, [("statistics.age", "d", math.nan)], "statistics.age"),
    (ROBOT, [("model.axis[0][0]", "d", 1e300)], "model"),
    # the model file's program (its resources) cannot be patched: it is this instance's
    (MODEL, [("program.op[0]", "i", 99)], "another model file"),
    (MODEL, [("program.start[0][0]", "i", 100000)], "another model file"),
    (MODEL, [("program.n", "i", 4)], "another model file"),
    (MODEL, [("pipe.id.p", "i", 84)], "id.p"),
    (MODEL, [("pipe.id.run_end[0][0]", "i", 100000)], "id.run_end"),
    (MODEL, [("pipe.warm_samples", "i", -1)], "warm_samples"),
    (MODEL, [("pipe.id.anchor_age", "i", INT_MAX)], "id.anchor_age"),
    (MODEL, [("pipe.warm_samples", "i", 100000)], "warm_samples"),
    (MODEL, [("pipe.statistics.stage", "i", 9)], "statistics.stage"),
    (MODEL, [("pipe.bank[0].follow", "i", 15)], "an index of pipe.bank[0]"),
    (MODEL, [("pipe.obs[0].n", "i", 0)], "obs[0].n"),
    (MODEL, [("pipe.identifying", "i", 2)], "identifying"),
    (MODEL, [("pipe.Y.row[0][0]", "d", math.nan)], "the model data (its byte"),
]
IDS = [f"{model[:5]}-{'+'.join(p[0] for p in patches)}={patches[-1][2]}"
       for model, patches, _ in CASES]


def _drive(set_inputs, model: str, t: float):
    if model == MODEL:  # the template's pendulum
        set_inputs({"position_1": 0.3 * math.sin(2 * t), "input_1": 2.0 * math.cos(3 * t)})
    elif model == OBS:
        set_inputs({"y": 0.5 * math.sin(3 * t), "u": math.cos(2 * t)})
    else:
        set_inputs({"q": [0.3 * math.sin(2 * t), 0.2 * math.sin(3 * t)],
                    "u": [math.sin(5 * t), math.cos(4 * t)]})


def _patched(model: str, serialized: bytes, patches) -> bytes:
    data = bytearray(serialized)
    for field, kind, value in patches:
        offset, size = field_location(model, field)
        assert size == struct.calcsize(FORMAT[kind]), (field, size)
        struct.pack_into(FORMAT[kind], data, offset, value)
    assert bytes(data) != serialized
    return forge(bytes(data))


# ---- FMI 2 ------------------------------------------------------------------------------------

def _fmi2_inputs(f: Raw, model: str):
    def set_inputs(values):
        flat = {}
        for name, value in values.items():
            if isinstance(value, list):
                flat.update({f"{name}[{i + 1}]": v for i, v in enumerate(value)})
            else:
                flat[f"{name}[1]" if name == "y" else name] = value
        assert f.set_real(flat) == OK, f.messages()
    return set_inputs


def _fmi2_run(model: str, parameters: dict, steps: int) -> tuple[Raw, float]:
    f = Raw(model)
    assert f.initialize(parameters) <= 1, f.messages()
    t = 0.0
    for _ in range(steps):
        _drive(_fmi2_inputs(f, model), model, t)
        assert f.do_step(t, H) == OK, f.messages()
        t += H
    return f, t


@pytest.mark.parametrize("model, patches, named", CASES, ids=IDS)
def test_fmi2_forged_state_is_refused_naming_the_field(model, patches, named):
    def run():
        f, t = _fmi2_run(model, SETUP[model], STEPS)
        good = f.serialize(f.get_state())
        victim = Raw(model, "victim")
        status, state = victim.deserialize(good)
        assert status == OK, victim.messages()  # the unpatched state is accepted
        victim.clear_log()
        status, state = victim.deserialize(_patched(model, good, patches), state)
        if status == OK:  # accepted: show what the model does with it before failing
            victim.call("fmi2SetFMUstate", state)
            step = victim.do_step(t, H)
            raise AssertionError(f"forged state accepted; doStep then returned {step}: "
                                 f"{victim.messages()[:300]!r}")
        assert status == ERROR, victim.messages()
        assert named in victim.errors() and "state refused" in victim.errors(), victim.errors()
        victim.assert_escaped()
        assert_usable_after_reset(victim)
    isolated(run)


@pytest.mark.parametrize("model, field", [(MODEL, "pipe.bank[0].member[0][0].z1"),
                                          (OBS, "pipe.bank.member[0][0].z1")])
def test_a_state_that_overflows_when_stepped_is_never_handed_out(model, field):
    """A forged state of an extreme but finite value is accepted; the step after it
    overflows a member's innovation statistics to inf.  Taking the state then either
    fails, naming the overflow, or gives a state that deserializes again: the FMU never
    hands out a state it would refuse (the fuzz run found ModelObserver doing so)."""
    def run():
        f, t = _fmi2_run(model, SETUP[model], STEPS)
        good = f.serialize(f.get_state())
        victim = Raw(model, "victim")
        status, state = victim.deserialize(_patched(model, good, [(field, "d", 1e300)]))
        assert status == OK, victim.messages()
        assert victim.call("fmi2SetFMUstate", state) == OK, victim.messages()
        _drive(_fmi2_inputs(victim, model), model, t)
        victim.do_step(t, H)
        again = ctypes.c_void_p()
        if victim.call("fmi2GetFMUstate", ctypes.byref(again)) == OK:
            status, _ = victim.deserialize(victim.serialize(again))
            assert status == OK, victim.messages()
        else:
            assert "computation overflowed" in victim.errors(), victim.errors()
        victim.assert_escaped()
        assert_usable_after_reset(victim)
    isolated(run)


def test_fmi2_forged_state_before_initialization_is_refused():
    """Before initialization only the setters have written: an internal field
    that differs from the start state cannot come from this FMU."""
    def run():
        f = Raw(OBS)
        assert f.setup() == OK and f.set({"identifier": 1}) == OK
        good = f.serialize(f.get_state())
        victim = Raw(OBS, "victim")
        assert victim.deserialize(good)[0] == OK, victim.messages()
        victim.clear_log()
        status, _ = victim.deserialize(_patched(OBS, good, [("pipe.info.blocks.pairs", "i", 10**6)]))
        assert status == ERROR, victim.messages()
        assert "before initialization" in victim.errors(), victim.errors()
        assert_usable_after_reset(victim)
    isolated(run)


# States the FMU writes itself, over the configurations whose fields differ.
CONFIGURATIONS = [
    (OBS, {}), (OBS, {"identifier": 1}), (OBS, {"identifier": 2}),
    (OBS, {"identifier": 2, "identifier_form": 1}), (OBS, {"identifier": 1, "scheme": 1}),
    (OBS, {"identifier": 1, "scheme": 2}),
    (OBS, {"identifier": 2, "nominal_model": 2, "n": 4, "l": 4}),
    (ROBOT, SETUP[ROBOT]), (ROBOT, {**SETUP[ROBOT], "identifier": 2}),
    (ROBOT, {**SETUP[ROBOT], "identifier": 0}),
    (ROBOT, {**SETUP[ROBOT], "statistics_interval": 0.0, "min_speed": 0.0,
             "reversal_margin": 0.0}),
    (ROBOT, {**SETUP[ROBOT], "identifier": 2, "n": 7, "base_count": 84,
             **{f"f_plus[{i}]": 1000.0 for i in range(3, 8)},
             **{f"base_columns[{k + 1}]": k for k in range(84)}}),
    (OBS, {"identifier": 2, "nominal_model": 2, "n": 2, "l": 4, "mff_drift": True}),
    ("Pendulum", {}), ("TwistingController", {}),
    (MODEL, {"t_id": 0.0}), (MODEL, {"identifier": 2}), (MODEL, {"scheme": 2}),
]


def _outputs(f: Raw) -> list[float]:
    names = [v.name for v in f.md.modelVariables
             if v.causality == "output" and v.type == "Real"]
    status, values = f.get_real(names)
    assert status == OK
    return values


@pytest.mark.parametrize("model, parameters", CONFIGURATIONS,
                         ids=[f"{m}-{'-'.join(f'{k}={v}' for k, v in p.items())}"[:90]
                              for m, p in CONFIGURATIONS])
def test_fmi2_states_the_fmu_wrote_are_accepted_and_continue_exactly(model, parameters):
    def run():
        f = Raw(model)
        assert f.initialize(parameters) <= 1, f.messages()
        t = 0.0
        for k in range(1500):
            if model in (OBS, ROBOT, MODEL):
                _drive(_fmi2_inputs(f, model), model, t)
            if k % 149 == 0:
                copy = Raw(model, "copy")
                status, state = copy.deserialize(f.serialize(f.get_state()))
                assert status == OK, (k, copy.errors())
                assert copy.call("fmi2SetFMUstate", state) == OK
                assert f.do_step(t, H) == OK and copy.do_step(t, H) == OK, copy.messages()
                assert _outputs(copy) == _outputs(f)
                copy.free()
            else:
                assert f.do_step(t, H) == OK, f.messages()
            t += H
    isolated(run)


# ---- FMI 3 ------------------------------------------------------------------------------------

def _fmi3_fmu(model: str) -> Path:
    path = Path(os.environ.get("STO_FMI3_DIR", REPO / "build" / "fmi3")) / f"{model}.fmu"
    assert path.exists(), f"{path} is missing: run ./build.sh fmus"
    return path


def _fmi3_set_inputs(f: RawFMU3):
    def set_inputs(values):
        full = {}
        for name, value in values.items():
            value = value if isinstance(value, list) else [value]
            full[name] = value + [0.0] * (f.size[name] - len(value))
        assert f.set("Float64", full) == OK, f.messages()
    return set_inputs


def _fmi3_run(model: str, steps: int) -> tuple[RawFMU3, float]:
    f = RawFMU3(_fmi3_fmu(model), "original")
    assert f.call("EnterInitializationMode", False, 0.0, 0.0, False, 0.0) == OK
    if model == OBS:
        assert f.set("Int32", {"identifier": [1]}) == OK, f.messages()
    elif model == ROBOT:
        assert f.set("Float64", {"f_plus": [1000.0] * f.size["f_plus"]}) == OK, f.messages()
    else:
        assert f.set("Float64", {k: [v] for k, v in SETUP[model].items()}) == OK, f.messages()
    assert f.call("ExitInitializationMode") == OK, f.messages()
    t = 0.0
    for _ in range(steps):
        _drive(_fmi3_set_inputs(f), model, t)
        assert f.do_step(t, H)[0] == OK, f.messages()
        t += H
    return f, t


def _fmi3_serialize(f: RawFMU3) -> bytes:
    state, size = ctypes.c_void_p(), ctypes.c_size_t()
    assert f.call("GetFMUState", ctypes.byref(state)) == OK
    assert f.call("SerializedFMUStateSize", state, ctypes.byref(size)) == OK
    data = (ctypes.c_uint8 * size.value)()
    assert f.call("SerializeFMUState", state, data, size.value) == OK
    return bytes(data)


def _fmi3_deserialize(f: RawFMU3, data: bytes):
    state = ctypes.c_void_p()
    buffer = (ctypes.c_uint8 * len(data)).from_buffer_copy(data)
    return f.call("DeserializeFMUState", buffer, len(data), ctypes.byref(state)), state


@pytest.mark.parametrize("model, patches, named", CASES, ids=IDS)
def test_fmi3_forged_state_is_refused_naming_the_field(model, patches, named):
    def run():
        f, t = _fmi3_run(model, STEPS)
        good = _fmi3_serialize(f)
        victim = RawFMU3(_fmi3_fmu(model), "victim")
        assert _fmi3_deserialize(victim, good)[0] == OK, victim.messages()
        victim.log.clear()
        status, state = _fmi3_deserialize(victim, _patched(model, good, patches))
        if status == OK:
            victim.call("SetFMUState", state)
            step = victim.do_step(t, H)[0]
            raise AssertionError(f"forged state accepted; doStep then returned {step}: "
                                 f"{victim.messages()[:300]!r}")
        errors = "\n".join(m for s, m in victim.log if s >= ERROR)
        assert status == ERROR, victim.messages()
        assert named in errors and "state refused" in errors, errors
        assert victim.call("Reset") == OK
        assert victim.initialize() == OK and victim.do_step(0.0, H)[0] == OK, victim.messages()
        victim.free()
        f.free()
    isolated(run)
