"""FMI 3.0 variants of the FMUs (build/fmi3/), through fmpy.

Same model files as the FMI 2.0 FMUs, so the same numbers: the FMI 3 runs are compared
with the FMI 2 runs element by element.  Then FMI 3's own state machine, fmi3DoStep's
outputs, bad input and FMU state round trips, with fmpy's raw functions
(tests/fmu/fmi_helpers.RawFMU3: status codes, every message recorded)."""
from __future__ import annotations

import ctypes
import math
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.model_description import read_build_description
from fmpy.validation import validate_fmu

from .fmi_helpers import ERROR, OK, RawFMU3, instances

FMI2_OBSERVER_ELEMENTS = {"y": 4, "x2_hat": 4, "theta_hat": 32}


@pytest.fixture
def make(observer_fmi3):
    """Observer instances on demand, all freed at the end of the test."""
    yield from instances(RawFMU3, observer_fmi3)


# ---- description ---------------------------------------------------------------------

def test_fmi3_fmus_validate_and_describe_their_sources(fmi3_fmu):
    assert validate_fmu(str(fmi3_fmu)) == []
    md = read_model_description(str(fmi3_fmu))
    assert md.fmiVersion == "3.0" and md.coSimulation.canGetAndSetFMUstate
    with zipfile.ZipFile(fmi3_fmu) as archive:
        names = set(archive.namelist())
    assert f"binaries/x86_64-linux/{md.coSimulation.modelIdentifier}.so" in names
    (config,) = read_build_description(str(fmi3_fmu))
    sources = config.sourceFileSets[0].sourceFiles
    assert sources[:2] == ["fmi3/fmi3_functions.c", "instance/instance.c"]
    assert all(f"sources/{name}" in names for name in sources)


def test_the_observer_has_arrays_with_the_fmi2_value_references(observer_fmi3, observer_fmu):
    md3 = {v.name: v for v in read_model_description(str(observer_fmi3)).modelVariables}
    md2 = {v.name: v for v in read_model_description(str(observer_fmu)).modelVariables}
    assert md3["time"].causality == "independent" and md3["time"].valueReference == 0
    for name, count in FMI2_OBSERVER_ELEMENTS.items():
        assert int(np.prod(md3[name].shape)) == count
        first = f"{name}[1]" if md3[name].shape and len(md3[name].shape) == 1 else f"{name}[1,1]"
        assert md3[name].valueReference == md2[first].valueReference
    assert md3["theta_hat"].shape == (4, 8)
    assert md3["h"].valueReference == md2["h"].valueReference and md3["h"].shape == ()


def test_the_fmi3_build_description_is_also_in_the_fmi2_fmu(observer_fmu):
    (config,) = read_build_description(str(observer_fmu))
    assert config.sourceFileSets[0].sourceFiles[0] == "fmi2/fmi2_functions.c"


# ---- same numbers as FMI 2 -------------------------------------------------------------

@pytest.mark.parametrize("model", ["Pendulum", "TwistingController"])
def test_bench_fmus_simulate_like_their_fmi2_variants(model):
    from tests.conftest import fmu_path

    fmi2 = simulate_fmu(str(fmu_path(model, 2)), stop_time=1.0, output_interval=0.01)
    fmi3 = simulate_fmu(str(fmu_path(model, 3)), stop_time=1.0, output_interval=0.01)
    assert fmi2.dtype.names == fmi3.dtype.names and len(fmi3) == 101
    for name in fmi2.dtype.names:
        np.testing.assert_array_equal(fmi3[name], fmi2[name], err_msg=name)
    assert np.ptp(fmi3[fmi3.dtype.names[1]]) > 0  # the model moved


def test_observer_with_input_arrays_matches_fmi2(observer_fmi3, observer_fmu):
    t = np.arange(0.0, 0.2, 1e-4)
    y = 0.1 * np.sin(5 * t)
    fmi2_input = np.array(list(zip(t, y)), dtype=[("time", float), ("y[1]", float)])
    fmi2 = simulate_fmu(str(observer_fmu), stop_time=0.2, input=fmi2_input,
                        output=["x2_hat[1]", "theta_hat[1,1]"])
    fmi3_input = np.zeros(len(t), dtype=[("time", float), ("y", float, (4,))])
    fmi3_input["time"], fmi3_input["y"][:, 0] = t, y
    fmi3 = simulate_fmu(str(observer_fmi3), stop_time=0.2, input=fmi3_input,
                        output=["x2_hat", "theta_hat"])
    assert np.ptp(fmi2["x2_hat[1]"]) > 0.1  # the input moved the observer
    np.testing.assert_array_equal(fmi3["x2_hat"][:, 0], fmi2["x2_hat[1]"])
    np.testing.assert_array_equal(fmi3["theta_hat"][:, 0, 0], fmi2["theta_hat[1,1]"])


# ---- state machine and fmi3DoStep ----------------------------------------------------------

def test_do_step_reports_no_event_no_termination_no_early_return(make):
    fmu = make()
    assert fmu.initialize(stop=1.0) == OK, fmu.messages()
    assert fmu.do_step(0.0, 0.01) == (OK, False, False, False, 0.01)
    assert fmu.get("Float64", ["time"]) == [0.01]
    assert fmu.do_step(0.01, 0.005)[4] == pytest.approx(0.015, abs=1e-15)


def test_a_refused_step_keeps_last_successful_time_and_enters_the_error_state(make):
    fmu = make()
    assert fmu.initialize() == OK
    assert fmu.do_step(0.0, 0.01)[0] == OK
    status, _, _, _, last = fmu.do_step(0.5, 0.01)  # not the instance's time
    assert status == ERROR and last == 0.01
    assert "currentCommunicationPoint = 0.5" in fmu.messages()
    assert fmu.do_step(0.01, 0.01)[0] == ERROR  # Error state: no more steps
    assert "not allowed in state Error" in fmu.log[-1][1]
    assert fmu.call("Reset") == OK and fmu.initialize() == OK
    assert fmu.do_step(0.0, 0.01)[0] == OK


def test_the_work_limit_refuses_a_long_step_before_any_work(make):
    fmu = make()
    assert fmu.initialize() == OK
    status, _, _, _, last = fmu.do_step(0.0, 1e4)  # 10^8 internal steps of 1e-4
    assert status == ERROR and last == 0.0
    assert "max_internal_steps" in fmu.messages()


@pytest.mark.parametrize("call, args, expected", [
    ("DoStep", None, "fmi3DoStep: illegal call sequence (not allowed in state Instantiated)"),
    ("ExitInitializationMode", (), "not allowed in state Instantiated"),
    ("Terminate", (), "fmi3Terminate: illegal call sequence"),
    ("EnterStepMode", (), "fmi3EnterStepMode: illegal call sequence"),
    ("EnterEventMode", (), "fmi3EnterEventMode is not supported (hasEventMode = false)"),
    ("EnterConfigurationMode", (), "not supported (no structural parameters)"),
])
def test_calls_out_of_sequence_are_refused_with_a_message(make, call, args, expected):
    fmu = make()
    if args is None:
        assert fmu.do_step(0.0, 0.01)[0] == ERROR
    else:
        assert fmu.call(call, *args) == ERROR
    assert expected in fmu.messages()


def test_terminate_then_only_reset_or_getters(make):
    fmu = make()
    assert fmu.initialize() == OK and fmu.do_step(0.0, 0.01)[0] == OK
    assert fmu.call("Terminate") == OK
    assert fmu.get("Float64", ["time"]) == [0.01]
    assert fmu.do_step(0.01, 0.01)[0] == ERROR
    assert "not allowed in state Terminated" in fmu.messages()


def test_other_interfaces_and_event_mode_are_refused_at_instantiation(observer_fmi3):
    fmu = RawFMU3(observer_fmi3, instantiate=False)
    assert not fmu.instantiate(event_mode=True)
    assert "eventModeUsed = true" in fmu.messages()
    assert not fmu.instantiate(n_required=1)
    assert "intermediate update" in fmu.messages()
    assert not fmu.instantiate(token="{wrong}")
    assert "GUID mismatch: got {wrong}" in fmu.messages()
    assert not fmu.instantiate(name="")
    assert "instanceName is NULL or empty" in fmu.messages()
    me = fmu.f["fmi3InstantiateModelExchange"](b"me", fmu.md.guid.encode(), None, False, False,
                                                None, fmu._logger)
    assert not me and "supports Co-Simulation only" in fmu.messages()


# ---- bad input ----------------------------------------------------------------------------

@pytest.mark.parametrize("kind, values, expected", [
    ("Float64", {"h": [0.0]}, "h = 0 is out of range (0, 1]"),
    ("Float64", {"h": [math.nan]}, "h = nan is not finite"),
    ("Float64", {"tau": [-1.0]}, "tau = -1 is out of range"),
    ("Float64", {"x2_hat": [0.0] * 4}, "x2_hat[1] is an output and cannot be set"),
    ("Float64", {"time": [1.0]}, "time (value reference 0) is the independent variable"),
    ("Int32", {"n": [7]}, "n = 7 is out of range [1, 4]"),
    ("Float64", {"n": [1.0]}, "n (value reference 2) is a Integer, not a Real"),
])
def test_bad_values_are_rejected_with_a_message_and_nothing_written(make, kind, values,
                                                                    expected):
    fmu = make()
    assert fmu.call("EnterInitializationMode", False, 0.0, 0.0, False, 0.0) == OK
    before = fmu.get("Float64", ["h", "tau"])
    assert fmu.set(kind, values) == ERROR
    assert expected in fmu.messages()
    assert fmu.get("Float64", ["h", "tau"]) == before


def test_an_array_element_out_of_range_names_the_element(make):
    fmu = make()
    rows = fmu.size["alpha1"]
    assert fmu.set("Float64", {"alpha1": [1.0] * (rows - 1) + [-1.0]}) == ERROR
    assert f"alpha1[{rows}] = -1 is out of range" in fmu.messages()


def test_n_values_must_match_the_arrays(make):
    fmu = make()
    assert fmu.initialize() == OK
    vrs = (ctypes.c_uint * 2)(fmu.vr["x2_hat"], fmu.vr["h"])
    values = (ctypes.c_double * 5)()
    assert fmu.call("GetFloat64", vrs, 2, values, 4) == ERROR
    assert "nValues = 4, but the 2 value references have 5 values" in fmu.messages()


def test_unknown_references_and_absent_types_are_refused(make):
    fmu = make()
    assert fmu.initialize() == OK
    vr = (ctypes.c_uint * 1)(fmu.vr["y"] + 1)  # an element of y in FMI 2, nothing in FMI 3
    value = (ctypes.c_double * 1)()
    assert fmu.call("GetFloat64", vr, 1, value, 1) == ERROR
    assert f"unknown value reference {fmu.vr['y'] + 1}" in fmu.messages()
    fmu.call("Reset")
    assert fmu.initialize() == OK
    assert fmu.call("GetFloat32", vr, 1, (ctypes.c_float * 1)(), 1) == ERROR
    assert "this FMU has no Float32 variables" in fmu.messages()


def test_fixed_parameters_cannot_change_after_initialization(make):
    fmu = make()
    assert fmu.initialize() == OK
    assert fmu.set("Float64", {"tau": [0.5]}) == ERROR
    assert "tau is a fixed parameter and cannot be set after initialization (state StepMode)" \
        in fmu.messages()


# ---- FMU state -----------------------------------------------------------------------------

def _run(fmu: RawFMU3, t0: float, steps: int, h: float = 1e-3) -> np.ndarray:
    out = []
    for k in range(steps):
        t = t0 + k * h
        assert fmu.set("Float64", {"y": [0.3 * math.sin(2 * t) + 0.1 * t, 0, 0, 0]}) == OK
        assert fmu.do_step(t, h)[0] == OK, fmu.messages()
        out.append(fmu.get("Float64", ["x1_hat", "x2_hat", "theta_hat"]))
    return np.array(out)


def test_get_set_and_serialized_state_round_trips_reproduce_the_run(make):
    fmu = make()
    assert fmu.initialize() == OK
    _run(fmu, 0.0, 50)
    state = ctypes.c_void_p()
    assert fmu.call("GetFMUState", ctypes.byref(state)) == OK
    first = _run(fmu, 0.05, 50)
    assert fmu.call("SetFMUState", state) == OK
    np.testing.assert_array_equal(_run(fmu, 0.05, 50), first)

    size = ctypes.c_size_t()
    assert fmu.call("SerializedFMUStateSize", state, ctypes.byref(size)) == OK
    data = (ctypes.c_uint8 * size.value)()
    assert fmu.call("SerializeFMUState", state, data, size.value) == OK
    other = make("other")
    restored = ctypes.c_void_p()
    assert other.call("DeserializeFMUState", data, size.value, ctypes.byref(restored)) == OK
    assert other.call("SetFMUState", restored) == OK
    np.testing.assert_array_equal(_run(other, 0.05, 50), first)
    assert other.call("FreeFMUState", ctypes.byref(restored)) == OK and not restored.value
    assert fmu.call("FreeFMUState", ctypes.byref(state)) == OK


def test_corrupted_or_fmi2_states_are_refused(make, observer_fmu):
    from .fmi_helpers import RawFMU

    fmu = make()
    assert fmu.initialize() == OK
    state = ctypes.c_void_p()
    size = ctypes.c_size_t()
    assert fmu.call("GetFMUState", ctypes.byref(state)) == OK
    assert fmu.call("SerializedFMUStateSize", state, ctypes.byref(size)) == OK
    data = (ctypes.c_uint8 * size.value)()
    assert fmu.call("SerializeFMUState", state, data, size.value) == OK
    data[size.value - 1] ^= 0xFF
    restored = ctypes.c_void_p()
    assert fmu.call("DeserializeFMUState", data, size.value, ctypes.byref(restored)) == ERROR
    assert "checksum mismatch" in fmu.messages()

    fmi2 = RawFMU(observer_fmu)  # the same model's FMI 2 state: same size, other magic
    try:
        assert fmi2.initialize() == OK
        s2 = ctypes.c_void_p()
        assert fmi2.call("fmi2GetFMUstate", ctypes.byref(s2)) == OK
        bytes2 = (ctypes.c_char * size.value)()
        assert fmi2.call("fmi2SerializeFMUstate", s2, bytes2, size.value) == OK
    finally:
        fmi2.free()
    fresh = make("fresh")
    assert fresh.call("DeserializeFMUState", ctypes.cast(bytes2, ctypes.POINTER(ctypes.c_uint8)),
                      size.value, ctypes.byref(restored)) == ERROR
    assert "not a serialized FMU state (bad magic)" in fresh.messages()


def test_foreign_state_pointers_are_refused(make):
    fmu, other = make(), make("other")
    state = ctypes.c_void_p()
    assert other.call("GetFMUState", ctypes.byref(state)) == OK
    assert fmu.call("SetFMUState", state) == ERROR
    assert "not a state of this instance" in fmu.messages()
