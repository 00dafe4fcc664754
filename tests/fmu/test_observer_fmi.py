"""FMI 2.0 behaviour of the SuperTwistingObserver FMU, through fmpy's raw functions."""
from __future__ import annotations

import ctypes
import math

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from .fmi_helpers import ERROR, OK, WARNING, RawFMU


@pytest.fixture
def fmu(observer_fmu):
    instance = RawFMU(observer_fmu)
    yield instance
    instance.free()


def _drive(fmu: RawFMU, steps: int, h: float = 1e-4, t0: float = 0.0, H: float | None = None):
    """Feeds y = 0.3 sin 2t + 0.1 t, u = 0 and returns the outputs after each step."""
    H = H or h
    out = []
    t = t0
    for k in range(steps):
        assert fmu.set_real({"y[1]": 0.3 * math.sin(2 * t) + 0.1 * t}) == OK
        assert fmu.do_step(t, H) == OK, fmu.messages()
        t = t0 + (k + 1) * H
        out.append(fmu.get_real(["x1_hat[1]", "x2_hat[1]", "z_eq[1]", "z_eq_filtered[1]"]))
    return np.array(out)


# ---- model description ----------------------------------------------------------------------

def test_model_description_is_valid_and_structured(observer_fmu):
    assert validate_fmu(str(observer_fmu)) == []
    md = read_model_description(str(observer_fmu))
    names = {v.name: v for v in md.modelVariables}
    assert md.variableNamingConvention == "structured"
    assert "theta_hat[1,2]" in names and "y[1]" in names and "x2_hat[4]" in names
    assert names["y[1]"].unit == "rad" and names["x2_hat[1]"].unit == "rad/s"
    assert names["u"].unit == "N.m"
    assert float(md.defaultExperiment.stepSize) == 1e-4
    assert names["h"].causality == "parameter" and names["h"].variability == "fixed"
    assert names["alpha1_used[1]"].causality == "calculatedParameter"
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
    import zipfile
    with zipfile.ZipFile(observer_fmu) as archive:  # sources for `fmpy compile`
        files = archive.namelist()
    assert "sources/fmi2/fmi2_layer.c" in files and "sources/models/observer.c" in files
    assert "binaries/linux64/SuperTwistingObserver.so" in files
    xml = zipfile.ZipFile(observer_fmu).read("modelDescription.xml").decode()
    assert '<File name="models/observer.c"/>' in xml


# ---- state machine --------------------------------------------------------------------------

@pytest.mark.parametrize("function, args", [
    ("fmi2DoStep", (0.0, 1e-4, 1)),
    ("fmi2ExitInitializationMode", ()),
    ("fmi2Terminate", ()),
])
def test_illegal_calls_before_initialization(fmu, function, args):
    assert fmu.call(function, *args) == ERROR
    assert f"{function}: illegal call sequence" in fmu.messages()


def test_get_in_instantiated_and_setup_after_init_are_illegal(fmu):
    value = (ctypes.c_double * 1)()
    vr = (ctypes.c_uint * 1)(fmu.vr["x1_hat[1]"])
    assert fmu.call("fmi2GetReal", vr, 1, value) == ERROR
    assert "fmi2GetReal: illegal call sequence (not allowed in state Instantiated)" in fmu.messages()
    assert fmu.call("fmi2Reset") == OK
    assert fmu.initialize() == OK
    assert fmu.setup() == ERROR
    assert "fmi2SetupExperiment: illegal call sequence" in fmu.messages()


def test_error_state_then_reset_makes_the_instance_usable(fmu):
    assert fmu.do_step(0.0, 1e-4) == ERROR
    # in the Error state only reset, get, FMU state functions and free are allowed
    assert fmu.call("fmi2EnterInitializationMode") == ERROR
    assert fmu.call("fmi2Reset") == OK
    assert fmu.initialize() == OK
    assert fmu.do_step(0.0, 1e-4) == OK


def test_null_pointers_and_zero_length_arrays(fmu):
    assert fmu.initialize() == OK
    assert fmu.call("fmi2GetReal", None, 0, None) == OK  # nothing asked, nothing done
    assert fmu.call("fmi2GetReal", None, 1, None) == ERROR
    assert "vr or value array is NULL with nvr = 1" in fmu.messages()
    assert fmu.call("fmi2Reset") == OK
    assert fmu.f["fmi2DoStep"](None, 0.0, 1e-4, 1) == ERROR  # NULL instance


def test_unknown_value_reference_and_wrong_type(fmu):
    assert fmu.initialize() == OK
    vr = (ctypes.c_uint * 1)(9999)
    value = (ctypes.c_double * 1)()
    assert fmu.call("fmi2GetReal", vr, 1, value) == ERROR
    assert "unknown value reference 9999" in fmu.messages()
    assert fmu.call("fmi2Reset") == OK and fmu.initialize() == OK
    vr[0] = fmu.vr["n"]
    assert fmu.call("fmi2GetReal", vr, 1, value) == ERROR
    assert "n (value reference 2) is a Integer, not a Real" in fmu.messages()


def test_fixed_parameter_cannot_be_set_after_initialization(fmu):
    assert fmu.initialize() == OK
    assert fmu.set_real({"tau": 0.01}) == ERROR
    assert "tau is a fixed parameter and cannot be set after initialization" in fmu.messages()


def test_outputs_cannot_be_set(fmu):
    assert fmu.set_real({"x2_hat[1]": 1.0}) == ERROR
    assert "x2_hat[1] is an output and cannot be set" in fmu.messages()


@pytest.mark.parametrize("name, value, words", [
    ("h", 0.0, "h = 0 is out of range (0, 1]"),
    ("h", -1e-4, "h = -0.0001 is out of range"),
    ("alpha1[1]", -1.0, "alpha1[1] = -1 is out of range [0"),
    ("tau", -0.5, "tau = -0.5 is out of range [0"),
    ("rho", 0.0, "rho = 0 is out of range (0"),
    ("R", 1.0, "R = 1 is out of range (0, 1)"),
    ("R", 0.0, "R = 0 is out of range (0, 1)"),
    ("p[2]", 1.0, "p[2] = 1 is out of range (0, 1)"),
    ("y[1]", float("nan"), "y[1] = nan is not finite"),
    ("u", float("inf"), "u = inf is not finite"),
    ("F[3]", float("-inf"), "F[3] = -inf is not finite"),
    ("phi[8]", float("nan"), "phi[8] = nan is not finite"),
])
def test_bad_values_are_rejected_and_leave_the_old_value(observer_fmu, name, value, words):
    fmu = RawFMU(observer_fmu)
    try:
        is_param = name in ("h", "alpha1[1]", "tau", "rho", "R", "p[2]")
        if not is_param:
            assert fmu.initialize() == OK
        before = None if is_param else fmu.get_real([name])[0]
        assert fmu.set_real({name: value}) == ERROR
        assert words in fmu.messages()
        if not is_param:
            assert fmu.get_real([name])[0] == before  # getters still work in the Error state
        assert fmu.call("fmi2Reset") == OK
        assert fmu.initialize() == OK  # usable again, with the start values
    finally:
        fmu.free()


@pytest.mark.parametrize("name, value, words", [
    ("n", 5, "n = 5 is out of range [1, 4]"),
    ("n", 0, "n = 0 is out of range [1, 4]"),
    ("identifier", 3, "identifier = 3 is out of range [0, 2]"),
    ("scheme", 0, "scheme = 0 is out of range [1, 2]"),
])
def test_bad_integers_are_rejected(fmu, name, value, words):
    assert fmu.set_integer({name: value}) == ERROR
    assert words in fmu.messages()


def test_all_or_nothing_when_one_value_of_a_call_is_bad(fmu):
    assert fmu.initialize() == OK
    assert fmu.set_real({"y[1]": 0.5, "u": float("nan")}) == ERROR
    assert fmu.get_real(["y[1]"]) == [0.0]  # the good value was not written either


def test_cross_parameter_problems_are_reported_at_initialization(fmu):
    assert fmu.initialize(integers={"n": 2}) == ERROR
    assert "n = 2: the built-in joint model (nominal_model = 1) has one degree of freedom" \
        in fmu.messages()
    assert fmu.call("fmi2Reset") == OK
    status = fmu.initialize(integers={"identifier": 1},
                            booleans={f"identify[{k}]": False for k in range(1, 9)})
    assert status == ERROR
    assert "no regressor is selected" in fmu.messages()
    assert fmu.call("fmi2Reset") == OK
    assert fmu.initialize(reals={"f_plus[1]": 0.0}) == ERROR
    assert "needs f_plus[1] > 0" in fmu.messages()


# ---- gains ----------------------------------------------------------------------------------

def test_gains_from_theorem_3_1(fmu):
    assert fmu.initialize() == OK  # alpha1 = alpha2 = 0, f_plus = 10, p = 0.5
    a1, a2 = fmu.get_real(["alpha1_used[1]", "alpha2_used[1]"])
    assert a1 == 20.0
    # hand computation: 1.1 * sqrt(2 / (20 - 10)) * (20 + 10) * (1 + 0.5) / (1 - 0.5)
    assert a2 == pytest.approx(1.1 * math.sqrt(0.2) * 30 * 3, rel=1e-15)


def test_gains_violating_condition_6_give_a_warning_that_says_by_how_much(fmu):
    status = fmu.initialize(reals={"alpha1[1]": 20.0, "alpha2[1]": 5.0})
    assert status == WARNING
    bound = math.sqrt(2 / 10) * 30 * 3
    assert f"alpha2[1] = 5 violates (6): the bound for alpha1 = 20, f_plus = 10, p = 0.5 is " \
           f"{bound:.6g} (short by {bound - 5:.6g}" in fmu.messages()
    assert fmu.get_real(["alpha2_used[1]"]) == [5.0]  # accepted as given
    assert fmu.do_step(0.0, 1e-4) == OK


# ---- stepping -------------------------------------------------------------------------------

def test_step_size_and_communication_point_checks(fmu):
    assert fmu.initialize() == OK
    assert fmu.do_step(0.0, 0.0) == ERROR
    assert "communicationStepSize = 0 must be > 0" in fmu.messages()
    assert fmu.call("fmi2Reset") == OK and fmu.initialize() == OK
    assert fmu.do_step(0.0, 0.1) == OK
    assert fmu.do_step(0.2, 0.1) == ERROR
    assert "currentCommunicationPoint = 0.20000000000000001 is not the instance's time 0.1" \
        in fmu.messages()
    assert fmu.call("fmi2Reset") == OK and fmu.initialize() == OK
    assert fmu.do_step(0.0, 0.1) == OK and fmu.do_step(0.1, 0.2) == OK
    assert fmu.do_step(0.1 + 0.2, 0.1) == OK  # 0.30000000000000004 is accepted


def test_steps_that_are_not_multiples_of_h(observer_fmu):
    """The FMU runs every internal step ending at or before t + H: four steps of 2.5e-5
    equal one step of 1e-4, bit for bit; 3e-4 then 1.5e-4 equals 4 steps (the rest carries)."""
    def run(steps):
        fmu = RawFMU(observer_fmu)
        assert fmu.initialize() == OK
        t, out = 0.0, []
        for H in steps:
            assert fmu.set_real({"y[1]": 0.01}) == OK
            assert fmu.do_step(t, H) == OK
            t += H
            out.append(fmu.get_real(["x1_hat[1]", "x2_hat[1]"]))
        fmu.free()
        return out

    assert run([2.5e-5] * 4)[-1] == run([1e-4])[-1]
    assert run([2.5e-5] * 3)[-1] == run([2.5e-5] * 2)[-1]  # no grid point crossed yet
    assert run([3e-4, 1.5e-4])[-1] == run([1e-4] * 4)[-1]
    assert run([1e-4] * 100)[-1] == run([1e-2])[-1]


# ---- FMU state ------------------------------------------------------------------------------

def test_get_and_set_fmu_state_continue_bit_identically(fmu):
    assert fmu.initialize(integers={"identifier": 1}) == OK
    _drive(fmu, 200)
    state = ctypes.c_void_p()
    assert fmu.call("fmi2GetFMUstate", ctypes.byref(state)) == OK
    first = _drive(fmu, 300, t0=0.02)
    assert fmu.call("fmi2SetFMUstate", state) == OK
    second = _drive(fmu, 300, t0=0.02)
    np.testing.assert_array_equal(first, second)
    assert fmu.call("fmi2FreeFMUstate", ctypes.byref(state)) == OK


def test_serialized_state_continues_in_another_instance_and_bad_buffers_are_rejected(observer_fmu):
    a = RawFMU(observer_fmu, "a")
    assert a.initialize(integers={"identifier": 2}) == OK
    _drive(a, 150)
    state = ctypes.c_void_p()
    assert a.call("fmi2GetFMUstate", ctypes.byref(state)) == OK
    size = ctypes.c_size_t()
    assert a.call("fmi2SerializedFMUstateSize", state, ctypes.byref(size)) == OK
    buffer = (ctypes.c_char * size.value)()
    assert a.call("fmi2SerializeFMUstate", state, buffer, size.value) == OK
    expected = _drive(a, 200, t0=0.015)

    b = RawFMU(observer_fmu, "b")
    restored = ctypes.c_void_p()
    assert b.call("fmi2DeSerializeFMUstate", buffer, size.value, ctypes.byref(restored)) == OK
    assert b.call("fmi2SetFMUstate", restored) == OK
    np.testing.assert_array_equal(_drive(b, 200, t0=0.015), expected)

    def rejected(data: bytes, words: str):
        c = RawFMU(observer_fmu, "c")
        raw = (ctypes.c_char * len(data)).from_buffer_copy(data)
        out = ctypes.c_void_p()
        assert c.call("fmi2DeSerializeFMUstate", raw, len(data), ctypes.byref(out)) == ERROR
        assert words in c.messages(), c.messages()
        assert c.call("fmi2Reset") == OK and c.initialize() == OK
        c.free()

    good = bytes(buffer)
    rejected(good[:-1], "wrong size")
    rejected(good + b"\0", "wrong size")
    flipped = bytearray(good)
    flipped[len(good) // 2] ^= 0x10
    rejected(bytes(flipped), "checksum mismatch")
    version = bytearray(good)
    version[8] ^= 0x01  # the format version follows the 8-byte magic
    rejected(bytes(version), "format version")
    rejected(b"\0" * len(good), "bad magic")
    a.free()
    b.free()


def test_reset_returns_to_the_freshly_instantiated_state(observer_fmu):
    fresh = RawFMU(observer_fmu, "fresh")
    assert fresh.initialize(integers={"identifier": 1}) == OK
    expected = _drive(fresh, 300)
    used = RawFMU(observer_fmu, "used")
    assert used.initialize(integers={"identifier": 2}, reals={"tau": 0.05}) == OK
    _drive(used, 500)
    assert used.call("fmi2Reset") == OK
    assert used.initialize(integers={"identifier": 1}) == OK
    np.testing.assert_array_equal(_drive(used, 300), expected)
    fresh.free()
    used.free()


def test_foreign_state_pointer_is_rejected_not_dereferenced(fmu):
    assert fmu.initialize() == OK
    bogus = ctypes.c_void_p(0x1234)
    assert fmu.call("fmi2SetFMUstate", bogus) == ERROR
    assert "not a state of this instance" in fmu.messages()


# ---- instances --------------------------------------------------------------------------------

def test_interleaved_instances_equal_one_at_a_time(observer_fmu):
    def make(identifier):
        f = RawFMU(observer_fmu, f"i{identifier}")
        assert f.initialize(integers={"identifier": identifier}) == OK
        return f

    alone = [_drive(make(k), 100) for k in (1, 2)]
    a, b = make(1), make(2)
    rows_a, rows_b = [], []
    for k in range(100):  # alternate one step each
        rows_a.append(_drive(a, 1, t0=k * 1e-4)[0])
        rows_b.append(_drive(b, 1, t0=k * 1e-4)[0])
    np.testing.assert_array_equal(np.array(rows_a), alone[0])
    np.testing.assert_array_equal(np.array(rows_b), alone[1])


def test_unsupported_functions_say_why(fmu):
    assert fmu.initialize() == OK
    assert fmu.call("fmi2GetDirectionalDerivative", None, 0, None, 0, None, None) == ERROR
    assert "not supported (providesDirectionalDerivative = false)" in fmu.messages()
    assert fmu.call("fmi2Reset") == OK
    assert fmu.call("fmi2SetRealInputDerivatives", None, 0, None, None) == ERROR
    assert "canInterpolateInputs = false" in fmu.messages()


def test_instantiate_checks_guid_type_and_callbacks(observer_fmu):
    fmu = RawFMU(observer_fmu, instantiate=False)
    assert not fmu.instantiate(guid="{wrong}")
    assert "GUID mismatch" in fmu.messages()
    assert not fmu.instantiate(callbacks=None)  # NULL callbacks: no crash, no instance
    assert not fmu.f["fmi2Instantiate"](b"x", 0, fmu.md.guid.encode(), None,
                                        ctypes.byref(fmu.callbacks), 0, 0)
    assert "supports Co-Simulation only" in fmu.messages()
    # NULL memory functions and a NULL resource location are accepted
    from fmpy.fmi2 import fmi2CallbackFunctions
    bare = fmi2CallbackFunctions()
    bare.logger = fmu.callbacks.logger
    c = fmu.f["fmi2Instantiate"](b"y", 1, fmu.md.guid.encode(), None, ctypes.byref(bare), 0, 0)
    assert c
    fmu.f["fmi2FreeInstance"](c)
