"""Bad input of every kind, over every FMU, through the raw fmi2 functions.

Each case runs in a forked child (abuse_fmi.isolated): a crash fails that case
only.  A case prepares an instance (freshly instantiated, in initialization
mode, or initialized with a saved FMU state), does one bad thing and checks:

* the status of the bad call (fmi2Error, or NULL from fmi2Instantiate);
* a logged message with status Error that names the problem;
* that the instance is usable again: restoring the saved FMU state (for the
  initialized ones) and fmi2Reset followed by a normal setup / init / doStep
  sequence all return fmi2OK.

Where the FMI standard wants the call accepted (nvr = 0, NULL memory
callbacks, NULL logger, ...), the case expects fmi2OK and a normal run.
"""
from __future__ import annotations

import ctypes
import math
import struct
from collections.abc import Callable
from dataclasses import dataclass

import pytest

from tools.abuse.abuse_fmi import (
    CLOCK_SIZE,
    DISCARD,
    ERROR,
    HEADER_SIZE,
    MODEL_EXCHANGE,
    MODELS,
    NORMAL_STEP,
    OK,
    WARNING,
    Callbacks,
    Raw,
    assert_usable_after_reset,
    forge,
    isolated,
    normal_run,
    parameter_offset,
)
from tools.abuse.state_format import offset

NAN, INF = float("nan"), float("inf")
OBS, PEN, CTL, ROBOT, *_ = MODELS

# Per model: an input, an output, a fixed Real parameter with its valid range, and the
# gap in its value references.
INFO = {
    OBS: dict(input="y[1]", output="x1_hat[1]", parameter="tau", unused_vr=7),
    PEN: dict(input="u", output="theta", parameter="M", unused_vr=17),
    CTL: dict(input="theta", output="u", parameter="k1", unused_vr=10),
    ROBOT: dict(input="q[1]", output="qd_hat[1]", parameter="tau", unused_vr=10),
    "ModelObserver": dict(input="position_1", output="velocity_1", parameter="tau_identifier",
                          unused_vr=2),
}


@dataclass
class Case:
    id: str
    model: str
    action: Callable[[Raw], int]   # does the bad thing; returns the status of the bad call
    words: str | None = None        # must appear in a message logged with status Error
    expect: int = ERROR
    before: str = "instantiated"    # "instantiated", "init_mode" or "initialized"
    callbacks: Callable[[], Callbacks] | None = None


def prepare(fmu: Raw, before: str):
    fmu.saved = None
    if before == "init_mode":
        assert fmu.setup() == OK and fmu.call("fmi2EnterInitializationMode") == OK
    elif before == "initialized":
        assert fmu.initialize() == OK, fmu.messages()
        fmu.saved = fmu.get_state()
    fmu.clear_log()


def run_case(case: Case):
    fmu = Raw(case.model, callbacks=case.callbacks() if case.callbacks else None)
    prepare(fmu, case.before)
    status = case.action(fmu)
    assert status == case.expect, (f"status {status}, expected {case.expect}", fmu.messages())
    if case.words is not None:
        log = fmu.errors() if case.expect >= ERROR else fmu.messages()
        assert case.words in log, f"{case.words!r} not logged; the log: {fmu.messages()!r}"
    fmu.assert_escaped()  # every message, of every case
    if fmu.saved is not None:  # back to the saved state, then one step from it
        assert fmu.call("fmi2SetFMUstate", fmu.saved) == OK, fmu.messages()
        assert fmu.do_step(0.0, NORMAL_STEP) == OK, fmu.messages()
    assert_usable_after_reset(fmu)
    fmu.assert_escaped()
    fmu.free()


CASES: list[Case] = []


def case(id, model, action, words=None, **kw):
    CASES.append(Case(f"{model}-{id}", model, action, words, **kw))


def illegal(function):
    return f"{function}: illegal call sequence (not allowed in state "


def out(fmu: Raw):
    return fmu.vrs([INFO[fmu.model]["output"]])


# ---- the FMI 2 state machine, on every FMU ---------------------------------------------------

def _error_then(fmu: Raw, then: Callable[[Raw], int]) -> int:
    assert fmu.do_step(0.0, -1.0) == ERROR  # into the Error state
    fmu.clear_log()
    return then(fmu)


def _terminated_then(fmu: Raw, then: Callable[[Raw], int]) -> int:
    assert fmu.call("fmi2Terminate") == OK
    return then(fmu)


for m in MODELS:
    inp = INFO[m]["input"]
    case("doStep-before-init", m, lambda f: f.do_step(0.0, NORMAL_STEP),
         illegal("fmi2DoStep") + "Instantiated)")
    case("doStep-in-init-mode", m, lambda f: f.do_step(0.0, NORMAL_STEP),
         illegal("fmi2DoStep") + "InitializationMode)", before="init_mode")
    case("exitInit-twice", m, lambda f: f.call("fmi2ExitInitializationMode"),
         illegal("fmi2ExitInitializationMode") + "StepComplete)", before="initialized")
    case("exitInit-before-enter", m, lambda f: f.call("fmi2ExitInitializationMode"),
         illegal("fmi2ExitInitializationMode") + "Instantiated)")
    case("enterInit-twice", m, lambda f: f.call("fmi2EnterInitializationMode"),
         illegal("fmi2EnterInitializationMode") + "InitializationMode)", before="init_mode")
    case("setup-after-init", m, lambda f: f.setup(), illegal("fmi2SetupExperiment") + "StepComplete)",
         before="initialized")
    case("setup-in-init-mode", m, lambda f: f.setup(),
         illegal("fmi2SetupExperiment") + "InitializationMode)", before="init_mode")
    case("getReal-in-instantiated", m,
         lambda f: f.call("fmi2GetReal", out(f), 1, (ctypes.c_double * 1)()),
         illegal("fmi2GetReal") + "Instantiated)")
    case("terminate-twice", m, lambda f: _terminated_then(f, lambda f: f.call("fmi2Terminate")),
         illegal("fmi2Terminate") + "Terminated)", before="initialized")
    case("terminate-before-init", m, lambda f: f.call("fmi2Terminate"),
         illegal("fmi2Terminate") + "Instantiated)")
    case("doStep-after-terminate", m,
         lambda f: _terminated_then(f, lambda f: f.do_step(0.0, NORMAL_STEP)),
         illegal("fmi2DoStep") + "Terminated)", before="initialized")
    case("setReal-after-terminate", m,
         lambda f, inp=inp: _terminated_then(f, lambda f: f.set_real({inp: 0.1})),
         illegal("fmi2SetReal") + "Terminated)", before="initialized")
    case("enterInit-after-terminate", m,
         lambda f: _terminated_then(f, lambda f: f.call("fmi2EnterInitializationMode")),
         illegal("fmi2EnterInitializationMode") + "Terminated)", before="initialized")
    case("doStep-in-error-state", m, lambda f: _error_then(f, lambda f: f.do_step(0.0, NORMAL_STEP)),
         illegal("fmi2DoStep") + "Error)", before="initialized")
    case("setReal-in-error-state", m,
         lambda f, inp=inp: _error_then(f, lambda f: f.set_real({inp: 0.1})),
         illegal("fmi2SetReal") + "Error)", before="initialized")
    case("cancelStep", m, lambda f: f.call("fmi2CancelStep"),
         illegal("fmi2CancelStep") + "StepComplete)", before="initialized")
    case("getStatus-in-instantiated", m,
         lambda f: f.call("fmi2GetStatus", 0, ctypes.byref(ctypes.c_int())),
         illegal("fmi2GetStatus") + "Instantiated)")
    case("getRealOutputDerivatives-in-init-mode", m,
         lambda f: f.call("fmi2GetRealOutputDerivatives", None, 0, None, None),
         illegal("fmi2GetRealOutputDerivatives") + "InitializationMode)", before="init_mode")


# ---- NaN, Inf and out-of-range values ---------------------------------------------------------

def bad_value(model, name, value, words, before="instantiated"):
    case(f"set-{name}={value}", model, lambda f: f.set({name: value}), words, before=before)


bad_value(OBS, "y[1]", NAN, "fmi2SetReal: y[1] = nan is not finite", before="initialized")
bad_value(OBS, "u", INF, "u = inf is not finite", before="initialized")
bad_value(OBS, "F[2]", -INF, "F[2] = -inf is not finite", before="init_mode")
bad_value(OBS, "phi[8]", NAN, "phi[8] = nan is not finite")
bad_value(OBS, "h", NAN, "h = nan is not finite")
bad_value(OBS, "tau", INF, "tau = inf is not finite")
bad_value(OBS, "h", 0.0, "h = 0 is out of range (0, 1]")
bad_value(OBS, "h", 2.0, "h = 2 is out of range (0, 1]")
bad_value(OBS, "h", -1e-4, "h = -0.0001 is out of range")
bad_value(OBS, "n", 0, "fmi2SetInteger: n = 0 is out of range [1, 4]")
bad_value(OBS, "n", 5, "n = 5 is out of range [1, 4]")
bad_value(OBS, "n", -2**31, "n = -2147483648 is out of range [1, 4]")
bad_value(OBS, "nominal_model", 3, "nominal_model = 3 is out of range [1, 2]")
bad_value(OBS, "scheme", 0, "scheme = 0 is out of range [1, 3]")
bad_value(OBS, "identifier", 3, "identifier = 3 is out of range [0, 2]")
bad_value(OBS, "l", 9, "l = 9 is out of range [1, 8]")
bad_value(OBS, "identifier_form", 0, "identifier_form = 0 is out of range")
bad_value(OBS, "identifier_start", 2**31 - 1, "identifier_start = 2147483647 is out of range")
bad_value(OBS, "p[1]", 1.0, "p[1] = 1 is out of range (0, 1)")
bad_value(OBS, "R", 0.0, "R = 0 is out of range (0, 1)")
bad_value(OBS, "rho", 0.0, "rho = 0 is out of range (0")
bad_value(OBS, "alpha2[4]", -1.0, "alpha2[4] = -1 is out of range [0")
bad_value(OBS, "convergence_window", 0.0, "convergence_window = 0 is out of range (0")
bad_value(OBS, "tau", 0.01, "tau is a fixed parameter and cannot be set after initialization",
          before="initialized")
bad_value(OBS, "x2_hat[1]", 1.0, "x2_hat[1] is an output and cannot be set")
bad_value(OBS, "alpha1_used[1]", 1.0, "alpha1_used[1] is a calculated parameter and cannot be set")
bad_value(PEN, "u", NAN, "u = nan is not finite", before="initialized")
bad_value(PEN, "u", -INF, "u = -inf is not finite", before="init_mode")
bad_value(PEN, "h", NAN, "h = nan is not finite")
bad_value(PEN, "h", 0.0, "h = 0 is out of range (0, 1]")
bad_value(PEN, "M", 0.0, "M = 0 is out of range (0")
bad_value(PEN, "M", INF, "M = inf is not finite")
bad_value(PEN, "L", -1.0, "L = -1 is out of range (0")
bad_value(PEN, "Vs", -1e-9, "Vs = -1.0000000000000001e-09 is out of range [0")
bad_value(PEN, "g", NAN, "g = nan is not finite")
bad_value(PEN, "damping", 2, "damping = 2 is out of range [0, 1]")
bad_value(PEN, "disturbance", -1, "disturbance = -1 is out of range [0, 2]")
bad_value(PEN, "d_period", 0.0, "d_period = 0 is out of range (0")
bad_value(PEN, "v_period", -1.0, "v_period = -1 is out of range (0")
bad_value(PEN, "M", 2.0, "M is a fixed parameter and cannot be set after initialization",
          before="initialized")
bad_value(PEN, "theta", 1.0, "theta is an output and cannot be set")
bad_value(PEN, "a_gravity", 1.0, "a_gravity is a calculated parameter and cannot be set")
bad_value(CTL, "theta", NAN, "theta = nan is not finite", before="initialized")
bad_value(CTL, "omega", -INF, "omega = -inf is not finite", before="initialized")
bad_value(CTL, "h", 0.0, "h = 0 is out of range (0, 1]")
bad_value(CTL, "h", 1.5, "h = 1.5 is out of range (0, 1]")
bad_value(CTL, "k1", -1.0, "k1 = -1 is out of range [0")
bad_value(CTL, "k2", NAN, "k2 = nan is not finite")
bad_value(CTL, "A1", INF, "A1 = inf is not finite")
bad_value(CTL, "h", 1e-3, "h is a fixed parameter and cannot be set after initialization",
          before="initialized")
bad_value(CTL, "u", 1.0, "u is an output and cannot be set")


def _all_or_nothing(f: Raw) -> int:
    """A valid and an invalid value in one call: neither is written."""
    inp = INFO[f.model]["input"]
    status = f.call("fmi2SetReal", f.vrs([inp, inp]), 2, (ctypes.c_double * 2)(0.25, NAN))
    got, (value,) = f.get_real([inp])  # getters stay allowed in the Error state
    assert got == OK and value != 0.25, value
    return status


for m in MODELS:
    case("set-valid-and-nan-in-one-call", m, _all_or_nothing, "is not finite", before="initialized")


# ---- cross-parameter checks at fmi2ExitInitializationMode --------------------------------------

def init_with(model, parameters, words, expect=ERROR, id=None):
    case(id or "init-" + ",".join(f"{k}={v}" for k, v in parameters.items()), model,
         lambda f: f.initialize(parameters), words, expect=expect)


init_with(OBS, {"n": 2}, "n = 2: the built-in joint model (nominal_model = 1) has one degree")
init_with(OBS, {"identifier": 1, "identify_b": False,
                **{f"identify[{k}]": False for k in (1, 2, 3)}},
          "identifier = 1 but no regressor is selected", id="init-identifier-without-regressor")
init_with(OBS, {"f_plus[1]": 0.0}, "a gain left at 0 needs f_plus[1] > 0")
init_with(OBS, {"f_plus[1]": 1e308}, "f_plus[1] = 1e+308 is too large: alpha1[1] = 2 f_plus[1] "
          "of Theorem 3.1 overflows")
init_with(OBS, {"nominal_model": 2, "l": 8, "identifier": 2,
                **{f"identify[{k}]": True for k in range(1, 9)}},
          "mff_drift needs 2 m <= 8 identified regressors, 8 are selected", id="init-mff-drift-m8")
init_with(OBS, {"identifier": 2, "identify[4]": True},
          "mff_drift needs 2 m <= 8 identified regressors, 5 are selected (the built-in joint's u",
          id="init-mff-drift-with-b")
init_with(OBS, {"alpha2[1]": 5.0}, "alpha2[1] = 5 violates (6)", expect=WARNING)


# ---- diverging models: fmi2DoStep says so ------------------------------------------------------

def diverge(model, parameters, inputs, words, id, steps=1):
    """Parameters (and inputs) that make the model's state or outputs non-finite:
    refused at fmi2ExitInitializationMode or by an fmi2DoStep within ``steps``
    steps, with a message that names the cause (not the integrator
    for an overflowing term, not "f_plus > 0" for a huge f_plus)."""
    def action(f: Raw) -> int:
        status = f.initialize(parameters)
        if status >= ERROR:
            return status
        assert f.set(inputs) == OK
        for k in range(steps):
            status = f.do_step(k * NORMAL_STEP, NORMAL_STEP)
            if status != OK:
                return status
        return status
    case(id, model, action, words)


# the input or the nominal model overflows: named, not "reduce h or the gains"
diverge(OBS, {"b": 1e300}, {"u": 1e300}, "observer: the nominal acceleration b u - c psi(y) = inf "
        "at t = 0.001 is out of floating-point range (b = 1e+300, u = 1e+300",
        "diverge-huge-input")
diverge(OBS, {"nominal_model": 2}, {"F[1]": 1e308}, "the nominal acceleration F[1] + "
        "theta_nominal phi = 1e+308 at t = 0.001 is out of floating-point range",
        "diverge-huge-F")
diverge(OBS, {"nominal_model": 2, "n": 2, "theta_nominal[2,3]": 1e300}, {"phi[3]": -1e300},
        "the nominal acceleration F[2] + theta_nominal phi = -inf", "diverge-huge-theta-phi")
diverge(OBS, {}, {"y[1]": 1e308}, "the measurement y[1] = 1e+308 at t = 0.001 is too large",
        "diverge-huge-measurement")
# the discretization itself: then h and the gains are the cause
diverge(OBS, {"scheme": 1, "alpha1[1]": 1e300, "alpha2[1]": 1e300}, {"y[1]": 1.0},
        "observer diverged at t = 0.001: x1_hat[1] = ", "diverge-huge-gains")
diverge(OBS, {"rho": 5e-324, "identifier": 1, "identifier_start": 0}, {},
        "gamma_trace = inf is not finite", "diverge-rho-denormal")
# the Pendulum: a term of the model that overflows is named, RK4 only when it is the cause
diverge(PEN, {}, {"u": 1e308}, "pendulum: the input torque u = 1e+308 gives u / J = ",
        "diverge-huge-torque")
diverge(PEN, {}, {"u": -1e308}, "the input torque u = -1e+308", "diverge-huge-negative-torque")
for d_period, steps in ((5e-324, 1), (1e-310, 40)):
    diverge(PEN, {"damping": 1, "d_period": d_period}, {},
            "pendulum: the damping d(t) = d_mean + d_amplitude sin(t / d_period) is ",
            f"diverge-d_period={d_period}", steps=steps)
diverge(PEN, {"disturbance": 2, "v_amplitude": 1e308}, {},
        "pendulum: the disturbance v(t) is 1e+308 at t = 0.001", "diverge-square-disturbance")
diverge(PEN, {"disturbance": 1, "v_amplitude": 1e308}, {}, "pendulum: the disturbance v(t) is ",
        "diverge-sine-disturbance", steps=400)
diverge(PEN, {"disturbance": 1, "v_frequency": 1e308}, {}, "pendulum: the disturbance v(t) is "
        "-nan", "diverge-disturbance-frequency", steps=2000)
diverge(PEN, {"h": 1.0, "Vs": 1e3}, {}, "RK4 needs h (a_viscous + |d|) below about 2.78, here "
        "h = 1, a_viscous = 1122.33", "diverge-rk4-unstable", steps=40000)
diverge(PEN, {"damping": 1, "d_amplitude": 1e300}, {}, "|d| <= 1e+300: reduce h below "
        "2.78e-300 or the damping", "diverge-huge-damping")
diverge(PEN, {"M": 1e-200, "L": 1e-100}, {}, "a_gravity = inf is not finite",
        "diverge-J-underflows")
# gains that cannot be computed: the reason, not always "needs f_plus > 0"
init_with(OBS, {"f_plus[1]": 10.0, "alpha1[1]": 5.0},
          "alpha2[1] = 0 is computed by Theorem 3.1 only when alpha1[1] exceeds f_plus[1]: "
          "alpha1[1] = 5, f_plus[1] = 10")
init_with(OBS, {"f_plus[1]": 1e308, "alpha1[1]": 1.7e308},
          "f_plus[1] = 1e+308, alpha1[1] = 1.7e+308: the alpha2 bound of (6) overflows")
init_with(OBS, {"nominal_model": 2, "n": 3, "f_plus[3]": 1.5e308},
          "f_plus[3] = 1.5e+308 is too large")


# ---- NULL pointers, unknown value references, wrong types ---------------------------------------

NULL_MESSAGE = "vr or value array is NULL with nvr = 1"
for m in MODELS:
    value_type = {"Real": ctypes.c_double, "Integer": ctypes.c_int, "Boolean": ctypes.c_int}
    for fn, ctype in (("fmi2GetReal", ctypes.c_double), ("fmi2SetReal", ctypes.c_double),
                      ("fmi2GetInteger", ctypes.c_int), ("fmi2SetBoolean", ctypes.c_int)):
        case(f"{fn}-NULL-vr", m, lambda f, fn=fn, ctype=ctype: f.call(fn, None, 1, (ctype * 1)()),
             f"{fn}: {NULL_MESSAGE}", before="initialized")
        case(f"{fn}-NULL-values", m, lambda f, fn=fn: f.call(fn, out(f), 1, None),
             f"{fn}: {NULL_MESSAGE}", before="initialized")
    case("getString-NULL-values", m, lambda f: f.call("fmi2GetString", out(f), 1, None),
         f"fmi2GetString: {NULL_MESSAGE}", before="initialized")
    case("getString", m, lambda f: f.call("fmi2GetString", out(f), 1, (ctypes.c_char_p * 1)()),
         "this FMU has no String variables", before="initialized")
    case("setString", m,
         lambda f: f.call("fmi2SetString", f.vrs([1]), 1, (ctypes.c_char_p * 1)(b"x")),
         "fmi2SetString: unknown value reference 1 (this FMU has no String variables)")
    unused = INFO[m]["unused_vr"]
    for vr in (unused, 9999, 0xFFFFFFFF):
        case(f"getReal-unknown-vr-{vr}", m,
             lambda f, vr=vr: f.call("fmi2GetReal", f.vrs([vr]), 1, (ctypes.c_double * 1)()),
             f"fmi2GetReal: unknown value reference {vr}", before="initialized")
    case("setReal-unknown-vr", m, lambda f: f.set_real({0xFFFFFFFE: 1.0}),
         "fmi2SetReal: unknown value reference 4294967294")
    case("getInteger-on-a-Real", m,
         lambda f: f.call("fmi2GetInteger", f.vrs(["h"]), 1, (ctypes.c_int * 1)()),
         "fmi2GetInteger: h (value reference 1) is a Real, not a Integer", before="initialized")
    case("setBoolean-on-a-Real", m, lambda f: f.set_boolean({"h": True}),
         "fmi2SetBoolean: h (value reference 1) is a Real, not a Boolean")
    case("setDebugLogging-NULL-categories", m, lambda f: f.call("fmi2SetDebugLogging", 1, 2, None),
         "fmi2SetDebugLogging: categories is NULL but nCategories = 2")
    case("setDebugLogging-unknown-category", m,
         lambda f: f.call("fmi2SetDebugLogging", 1, 2, (ctypes.c_char_p * 2)(b"logAll", b"logX")),
         'fmi2SetDebugLogging: unknown log category "logX"')
    case("setDebugLogging-NULL-category", m,
         lambda f: f.call("fmi2SetDebugLogging", 1, 1, (ctypes.c_char_p * 1)(None)),
         'unknown log category "(NULL)"')
    case("getStatus-NULL-value", m, lambda f: f.call("fmi2GetStatus", 0, None),
         "fmi2GetStatus: value is NULL", before="initialized")
    case("getRealStatus-NULL-value", m, lambda f: f.call("fmi2GetRealStatus", 2, None),
         "fmi2GetRealStatus: value is NULL", before="initialized")
    case("getDirectionalDerivative", m,
         lambda f: f.call("fmi2GetDirectionalDerivative", None, 0, None, 0, None, None),
         "fmi2GetDirectionalDerivative is not supported", before="initialized")
    case("setRealInputDerivatives", m,
         lambda f: f.call("fmi2SetRealInputDerivatives", None, 1, None, None),
         "fmi2SetRealInputDerivatives is not supported", before="initialized")
    # a status that is not defined is discarded, not an error
    case("getIntegerStatus-undefined", m,
         lambda f: f.call("fmi2GetIntegerStatus", 0, ctypes.byref(ctypes.c_int())),
         expect=DISCARD, before="initialized")

case("getReal-on-an-Integer", OBS,
     lambda f: f.call("fmi2GetReal", f.vrs(["n"]), 1, (ctypes.c_double * 1)()),
     "fmi2GetReal: n (value reference 2) is a Integer, not a Real", before="initialized")
case("getReal-on-a-Boolean", OBS,
     lambda f: f.call("fmi2GetReal", f.vrs(["identify[2]"]), 1, (ctypes.c_double * 1)()),
     "identify[2] (value reference 84) is a Boolean, not a Real", before="initialized")
case("setReal-on-a-Boolean-output", OBS, lambda f: f.set_real({"converged": 1.0}),
     "converged (value reference 362) is a Boolean, not a Real")
case("getBoolean-on-an-Integer", PEN,
     lambda f: f.call("fmi2GetBoolean", f.vrs(["damping"]), 1, (ctypes.c_int * 1)()),
     "damping (value reference 9) is a Integer, not a Boolean", before="initialized")


# ---- fmi2Instantiate ---------------------------------------------------------------------------

def instantiated(f: Raw, pointer) -> int:
    """fmi2Error for NULL; else frees the new instance and says fmi2OK."""
    if not pointer:
        return ERROR
    f.f["fmi2FreeInstance"](pointer)
    return OK


for m in MODELS:
    case("instantiate-wrong-GUID", m,
         lambda f: instantiated(f, f.instantiate(guid=b"{00000000-0000-0000-0000-000000000000}")),
         "fmi2Instantiate: GUID mismatch: got {00000000-0000-0000-0000-000000000000}")
    case("instantiate-NULL-GUID", m, lambda f: instantiated(f, f.instantiate(guid=None)),
         "GUID mismatch: got (NULL)")
    case("instantiate-NULL-name", m, lambda f: instantiated(f, f.instantiate(name=None)),
         "fmi2Instantiate: instanceName is NULL or empty")
    case("instantiate-empty-name", m, lambda f: instantiated(f, f.instantiate(name=b"")),
         "instanceName is NULL or empty")
    case("instantiate-ModelExchange", m,
         lambda f: instantiated(f, f.instantiate(fmu_type=MODEL_EXCHANGE)),
         "supports Co-Simulation only (fmuType = 0)")
    case("instantiate-type-42", m, lambda f: instantiated(f, f.instantiate(fmu_type=42)),
         "supports Co-Simulation only (fmuType = 42)")
    # NULL callbacks: nobody to tell, NULL is all there is
    case("instantiate-NULL-callbacks", m, lambda f: instantiated(f, f.instantiate(callbacks=None)))


def _life_with(callbacks: Callbacks, resources=b"default") -> Callable[[Raw], int]:
    """An instance made with these callbacks lives a normal life, bad calls included."""
    def action(f: Raw) -> int:
        other = Raw(f.model, instantiate=False, callbacks=callbacks)
        other.c = other.instantiate(callbacks=callbacks, resources=resources)
        assert other.c
        statuses = normal_run(other)
        assert statuses == [OK] * len(statuses), statuses
        state = other.get_state()
        assert other.deserialize(other.serialize(state), state)[0] == OK
        assert other.do_step(0.0, -1.0) == ERROR  # errors still come back as statuses
        assert_usable_after_reset(other)
        assert other.call("fmi2FreeFMUstate", ctypes.byref(state)) == OK
        other.free()
        return OK
    return action


def _callbacks_without(*fields):
    def make():
        cb = Callbacks()
        for name in fields:
            setattr(cb.struct, name, type(getattr(cb.struct, name))())  # a NULL function pointer
        return cb
    return make


for m in MODELS:
    case("NULL-allocate-and-free-accepted", m, lambda f: _life_with(_callbacks_without(
        "allocateMemory", "freeMemory")())(f), expect=OK)
    case("NULL-free-only-accepted", m, lambda f: _life_with(_callbacks_without("freeMemory")())(f),
         expect=OK)
    case("NULL-logger-accepted", m, lambda f: _life_with(_callbacks_without("logger")())(f),
         expect=OK)
    case("all-callbacks-NULL-accepted", m, lambda f: _life_with(Callbacks(False, False))(f),
         expect=OK)
    if Raw(m, instantiate=False).reads_resources:
        case("NULL-resource-location-refused", m, lambda f: _no_resources(f),
             words="no resource location given")
    else:
        case("NULL-resource-location-accepted", m, lambda f: _life_with(Callbacks(), None)(f),
             expect=OK)


def _no_resources(f: Raw) -> int:
    """A model that reads its resources: no location, no instance (and a message)."""
    assert not f.instantiate(name="other", resources=None)
    return ERROR


# ---- steps and experiment times ----------------------------------------------------------------

def after_one_step(then: Callable[[Raw], int]) -> Callable[[Raw], int]:
    def action(f: Raw) -> int:
        assert f.do_step(0.0, NORMAL_STEP) == OK
        return then(f)
    return action


for m in MODELS:
    for H, words in ((0.0, "fmi2DoStep: communicationStepSize = 0 must be > 0 and finite"),
                     (-1e-4, "communicationStepSize = -0.0001 must be > 0"),
                     (NAN, "communicationStepSize = nan must be > 0"),
                     (INF, "communicationStepSize = inf must be > 0"),
                     (-INF, "communicationStepSize = -inf must be > 0"),
                     (1e300, "needs more than 2^53 internal steps")):
        case(f"doStep-H={H}", m, lambda f, H=H: f.do_step(0.0, H), words,
             before="initialized")
    for t, words in ((NAN, "currentCommunicationPoint = nan is not the instance's time 0"),
                     (INF, "currentCommunicationPoint = inf is not"),
                     (0.5, "currentCommunicationPoint = 0.5 is not the instance's time 0")):
        case(f"doStep-t={t}", m, lambda f, t=t: f.do_step(t, NORMAL_STEP), words,
             before="initialized")
    case("doStep-repeats-a-step", m, after_one_step(lambda f: f.do_step(0.0, NORMAL_STEP)),
         "currentCommunicationPoint = 0 is not the instance's time 0.001", before="initialized")
    case("doStep-past-stopTime", m,
         lambda f: (f.initialize(stop=0.01), f.do_step(0.0, 0.02))[1],
         "fmi2DoStep: step to 0.02 goes past stopTime = 0.01")
    case("doStep-tiny-H-accepted", m,
         lambda f: max(f.do_step(0.0, 5e-324), f.do_step(5e-324, 1e-20)), expect=OK,
         before="initialized")
    case("setup-startTime-nan", m, lambda f: f.setup(NAN),
         "fmi2SetupExperiment: startTime = nan is not finite")
    case("setup-stopTime-before-startTime", m, lambda f: f.setup(1.0, 0.5),
         "stopTime = 0.5 must be finite and >= startTime = 1")
    case("setup-stopTime-inf", m, lambda f: f.setup(0.0, INF), "stopTime = inf must be finite")

case("doStep-2^53-internal-steps", OBS,
     lambda f: (f.initialize({"h": 1e-300}), f.do_step(0.0, NORMAL_STEP))[1],
     "step to 0.001 needs more than 2^53 internal steps of h = 1e-300")
case("doStep-huge-start-time", PEN,
     lambda f: (f.initialize(start=1e300), f.do_step(1e300, 1e290))[1],
     "needs more than 2^53 internal steps")


# ---- FMU states: serialized, foreign, freed, forged ----------------------------------------------

def serialized(f: Raw) -> bytes:
    assert f.do_step(0.0, NORMAL_STEP) == OK
    state = f.get_state()
    data = f.serialize(state)
    assert f.call("fmi2FreeFMUstate", ctypes.byref(state)) == OK
    return data


def deserialize_mutated(mutate: Callable[[bytes], bytes]) -> Callable[[Raw], int]:
    def action(f: Raw) -> int:
        status, state = f.deserialize(mutate(serialized(f)))
        assert not state, "a rejected state must not be handed out"
        return status
    return action


def flip(offset, bit=0):
    def mutate(data: bytes) -> bytes:
        b = bytearray(data)
        b[offset if offset >= 0 else len(b) + offset] ^= 1 << bit
        return bytes(b)
    return mutate


for m in MODELS:
    for id, mutate, words in (
            ("truncated-by-1", lambda d: d[:-1], "fmi2DeSerializeFMUstate: wrong size"),
            ("truncated-to-header", lambda d: d[:HEADER_SIZE], f"wrong size {HEADER_SIZE}"),
            ("empty", lambda d: b"", "wrong size 0"),
            ("oversized-by-1", lambda d: d + b"\0", "wrong size"),
            ("oversized-x2", lambda d: d + d, "wrong size"),
            ("flip-magic", flip(0), "not a serialized FMU state (bad magic)"),
            ("flip-version", flip(offset("version"), 3), "format version 10, expected 2"),
            ("flip-size-field", flip(offset("size"), 1), "state of another FMU or build"),
            ("flip-guid-hash", flip(offset("guid_hash"), 7), "state of another FMU or build"),
            ("flip-checksum", flip(offset("checksum")), "checksum mismatch (corrupted state)"),
            ("flip-clock-state", flip(offset("state"), 2), "checksum mismatch"),
            ("flip-clock-steps", flip(offset("steps"), 5), "checksum mismatch"),
            ("flip-first-data-byte", flip(HEADER_SIZE + CLOCK_SIZE, 6), "checksum mismatch"),
            ("flip-last-byte", flip(-1, 7), "checksum mismatch"),
            ("zeros", lambda d: bytes(len(d)), "bad magic"),
            ("forged-clock-state-0", lambda d: forge(d[:HEADER_SIZE] + bytes(4) + d[HEADER_SIZE + 4:]),
             "invalid instance state in buffer"),
            ("forged-clock-state-two-bits",
             lambda d: forge(d[:HEADER_SIZE] + struct.pack("<I", 0b101) + d[HEADER_SIZE + 4:]),
             "invalid instance state in buffer"),
            ("forged-clock-state-Fatal",
             lambda d: forge(d[:HEADER_SIZE] + struct.pack("<I", 1 << 8) + d[HEADER_SIZE + 4:]),
             "invalid instance state in buffer"),
    ):
        case(f"deserialize-{id}", m, deserialize_mutated(mutate), words, before="initialized")

    case("deserialize-NULL-buffer", m,
         lambda f: f.call("fmi2DeSerializeFMUstate", None, 100, ctypes.byref(ctypes.c_void_p())),
         "fmi2DeSerializeFMUstate: buffer or FMUstate is NULL", before="initialized")
    case("deserialize-NULL-FMUstate", m,
         lambda f: f.call("fmi2DeSerializeFMUstate", (ctypes.c_char * 8)(), 8, None),
         "buffer or FMUstate is NULL", before="initialized")
    case("serialize-wrong-size", m,
         lambda f: f.call("fmi2SerializeFMUstate", f.saved, (ctypes.c_char * 8)(), 8),
         "fmi2SerializeFMUstate: buffer size 8, expected", before="initialized")
    case("serialize-NULL-buffer", m,
         lambda f: f.call("fmi2SerializeFMUstate", f.saved, None, 0),
         "fmi2SerializeFMUstate: FMUstate or buffer is NULL or foreign", before="initialized")
    case("serializedSize-NULL-size", m,
         lambda f: f.call("fmi2SerializedFMUstateSize", f.saved, None),
         "fmi2SerializedFMUstateSize: FMUstate or size is NULL or foreign", before="initialized")
    case("getFMUstate-NULL", m, lambda f: f.call("fmi2GetFMUstate", None),
         "fmi2GetFMUstate: FMUstate is NULL", before="initialized")
    case("setFMUstate-NULL", m, lambda f: f.call("fmi2SetFMUstate", None),
         "fmi2SetFMUstate: FMUstate is NULL or not a state of this instance", before="initialized")


def _foreign_state(model: str):
    other = Raw(model, "other")
    assert other.initialize() == OK
    return other, other.get_state()


def _foreign(call: Callable[[Raw, ctypes.c_void_p], int]) -> Callable[[Raw], int]:
    def action(f: Raw) -> int:
        other, state = _foreign_state(f.model)
        status = call(f, state)
        # the other instance's state is untouched and still works there
        assert other.call("fmi2SetFMUstate", state) == OK
        other.free()
        return status
    return action


_GARBAGE = ctypes.create_string_buffer(4096)  # readable memory that no instance handed out
for m in MODELS:
    for pointer_name, pointer in (("foreign", None),
                                  ("garbage", ctypes.c_void_p(ctypes.addressof(_GARBAGE))),
                                  ("0x1234", ctypes.c_void_p(0x1234))):
        def with_pointer(call, pointer=pointer):
            if pointer is None:
                return _foreign(call)
            return lambda f: call(f, pointer)
        case(f"setFMUstate-{pointer_name}-pointer", m,
             with_pointer(lambda f, s: f.call("fmi2SetFMUstate", s)),
             "fmi2SetFMUstate: FMUstate is NULL or not a state of this instance",
             before="initialized")
        case(f"getFMUstate-into-{pointer_name}-pointer", m,
             with_pointer(lambda f, s: f.call("fmi2GetFMUstate", ctypes.byref(ctypes.c_void_p(s.value)))),
             "fmi2GetFMUstate: *FMUstate is neither NULL nor a state of this instance",
             before="initialized")
        case(f"freeFMUstate-{pointer_name}-pointer", m,
             with_pointer(lambda f, s: f.call("fmi2FreeFMUstate", ctypes.byref(ctypes.c_void_p(s.value)))),
             "fmi2FreeFMUstate: not a state of this instance", before="initialized")
        case(f"serializedSize-{pointer_name}-pointer", m,
             with_pointer(lambda f, s: f.call("fmi2SerializedFMUstateSize", s,
                                              ctypes.byref(ctypes.c_size_t()))),
             "FMUstate or size is NULL or foreign", before="initialized")
        case(f"deserialize-into-{pointer_name}-pointer", m,
             with_pointer(lambda f, s: f.call(
                 "fmi2DeSerializeFMUstate", *(lambda d: ((ctypes.c_char * len(d)).from_buffer_copy(d), len(d)))(
                     serialized(f)), ctypes.byref(ctypes.c_void_p(s.value)))),
             "fmi2DeSerializeFMUstate: *FMUstate is not a state of this instance",
             before="initialized")


def _use_after_free(f: Raw) -> int:
    state = f.get_state()
    stale = ctypes.c_void_p(state.value)
    assert f.call("fmi2FreeFMUstate", ctypes.byref(state)) == OK and not state
    assert f.call("fmi2FreeFMUstate", ctypes.byref(state)) == OK  # *state is NULL now: harmless
    return f.call("fmi2SetFMUstate", stale)


def _free_twice(f: Raw) -> int:
    state = f.get_state()
    copy = ctypes.c_void_p(state.value)
    assert f.call("fmi2FreeFMUstate", ctypes.byref(state)) == OK
    return f.call("fmi2FreeFMUstate", ctypes.byref(copy))


def _state_of_another_fmu(f: Raw) -> int:
    other_model = MODELS[(MODELS.index(f.model) + 1) % len(MODELS)]
    other = Raw(other_model, "other")
    assert other.initialize() == OK
    data = other.serialize(other.get_state())
    status, state = f.deserialize(data)
    assert not state
    return status


for m in MODELS:
    case("setFMUstate-after-free", m, _use_after_free,
         "FMUstate is NULL or not a state of this instance", before="initialized")
    case("freeFMUstate-twice-through-a-copy", m, _free_twice,
         "fmi2FreeFMUstate: not a state of this instance", before="initialized")
    case("deserialize-state-of-another-FMU", m, _state_of_another_fmu,
         "fmi2DeSerializeFMUstate: wrong size", before="initialized")


@pytest.mark.parametrize("c", CASES, ids=[c.id for c in CASES])
def test_bad_input(c: Case):
    isolated(run_case, c)


def test_there_are_enough_cases():
    assert len(CASES) >= 40
    assert {c.model for c in CASES} == set(MODELS)


# ---- a NULL instance: every function returns fmi2Error (there is nobody to log to) ---------------

def _component_functions():
    f = Raw(OBS, instantiate=False)
    return sorted(name for name, fn in f.f.items()
                  if fn.argtypes and fn.argnames[0] == "c" and name != "fmi2FreeInstance")


def _null_arguments(fn):
    return [0.0 if t is ctypes.c_double else 0 if t in (ctypes.c_int, ctypes.c_uint, ctypes.c_size_t)
            else None for t in fn.argtypes[1:]]


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("function", _component_functions())
def test_null_instance(model, function):
    def run():
        f = Raw(model, instantiate=False)
        fn = f.f[function]
        assert fn(None, *_null_arguments(fn)) == ERROR
        f.f["fmi2FreeInstance"](None)  # harmless
    isolated(run)


# ---- zero-length arrays with NULL pointers are fine everywhere ---------------------------------

ARRAY_FUNCTIONS = ["fmi2GetReal", "fmi2GetInteger", "fmi2GetBoolean", "fmi2GetString",
                   "fmi2SetReal", "fmi2SetInteger", "fmi2SetBoolean", "fmi2SetString"]


@pytest.mark.parametrize("model", MODELS)
def test_zero_length_arrays_are_accepted(model):
    def run():
        f = Raw(model)
        assert f.initialize() == OK
        for function in ARRAY_FUNCTIONS:
            assert f.call(function, None, 0, None) == OK, (function, f.messages())
        assert f.call("fmi2SetDebugLogging", 1, 0, None) == OK  # all categories
        assert f.do_step(0.0, NORMAL_STEP) == OK
        assert not f.errors()
        f.free()
    isolated(run)


# ---- forged states: a valid checksum over bad data ---------------------------------------------

# Parameters whose forged value lies outside their declared range, and the size of the field.
FORGED = {
    OBS: [("n", 1, 3, 4, 1 << 20), ("h", 1e-4, 2e-4, 8, -1.0),
          ("max_internal_steps", 5, 6, 4, 0)],
    PEN: [("h", 1e-5, 2e-5, 8, 0.0), ("M", 1.0, 2.0, 8, NAN), ("max_internal_steps", 5, 6, 4, -1)],
    CTL: [("h", 1e-4, 2e-4, 8, -1e-4), ("max_internal_steps", 5, 6, 4, -2**31)],
}
FORGED_CASES = [(m, *spec) for m, specs in FORGED.items() for spec in specs]


@pytest.mark.parametrize("model, name, a, b, size, bad", FORGED_CASES,
                         ids=[f"{c[0]}-{c[1]}={c[5]}" for c in FORGED_CASES])
def test_forged_state_with_out_of_range_parameter_is_rejected(model, name, a, b, size, bad):
    """The checksum (FNV-1a) detects accidents, not intent: anyone can recompute it.
    A state whose parameters break the variable table's ranges must be refused,
    as fmi2SetReal refuses them; the model then never sees n = 2^20 rows."""
    offset = parameter_offset(model, name, a, b, size)

    def run():
        f = Raw(model)
        assert f.initialize() == OK
        data = bytearray(serialized(f))
        struct.pack_into("<i" if size == 4 else "<d", data, offset, bad)
        status, state = f.deserialize(forge(bytes(data)))
        if status == OK:  # accepted: show what the model does with it before failing
            f.call("fmi2SetFMUstate", state)
            f.clear_log()
            step = f.do_step(NORMAL_STEP, NORMAL_STEP)
            raise AssertionError(f"forged state with {name} = {bad} accepted; doStep then "
                                 f"returned {step}: {f.messages()[:300]!r}")
        assert status == ERROR and name in f.errors(), f.messages()
        assert_usable_after_reset(f)
    isolated(run)


@pytest.mark.parametrize("model", MODELS)
def test_forged_state_with_inconsistent_clock_is_rejected(model):
    """The clock of a state says where the instance is: comm_time must be
    start_time + steps * h (up to the step tolerance).  A forged comm_time far
    ahead of `steps` makes the next fmi2DoStep run every internal step in
    between: up to 2^53 of them, a hang (the fuzzer's timeouts)."""
    def run():
        f = Raw(model)
        assert f.initialize() == OK
        data = bytearray(serialized(f))
        struct.pack_into("<d", data, offset("comm_time"), 1e9)
        status, state = f.deserialize(forge(bytes(data)))
        if status == OK:
            raise AssertionError("forged state with comm_time = 1e9 (steps unchanged) accepted: a "
                                 "doStep(1e9, 1e-3) from it would run 1e13 internal steps or more")
        assert status == ERROR and f.errors(), f.messages()
        assert_usable_after_reset(f)
    isolated(run)


# ---- OK never comes with a non-finite output ---------------------------------------------------

NON_FINITE = [
    (PEN, {"M": 1e-200, "L": 1e-100}, ["a_gravity", "b_input", "acceleration"]),
    (CTL, {"A1": 1e308, "w1": 1e308}, ["u", "theta_d", "omega_d"]),
    (OBS, {"rho": 5e-324, "identifier": 1, "identifier_start": 0}, ["gamma_trace"]),
]


@pytest.mark.parametrize("model, parameters, outputs", NON_FINITE, ids=[c[0] for c in NON_FINITE])
def test_ok_status_never_comes_with_non_finite_outputs(model, parameters, outputs):
    """Finite parameters within their ranges whose products overflow: the FMU may
    refuse them (fmi2Error with a message), but it must not report fmi2OK and
    hand out inf or NaN (an importer that trusts the status propagates them)."""
    def run():
        f = Raw(model)
        statuses = [("init", f.initialize(parameters))]
        if statuses[-1][1] < ERROR:
            statuses.append(("doStep", f.do_step(0.0, NORMAL_STEP)))
        for where, status in statuses:
            if status >= ERROR:
                assert f.errors(), "an error without a message"
                return
            got, values = f.get_real(outputs)
            bad = {n: v for n, v in zip(outputs, values) if not math.isfinite(v)}
            assert not bad, f"after {where} returned {status}: {bad}"
    isolated(run)


# ---- which FMUs are under test ----------------------------------------------------------------

def test_the_fmus_under_test(observer_fmu):
    """Under tools/abuse/sanitize.sh every test must load the sanitized FMUs."""
    import os

    from tools.abuse.abuse_fmi import fmu_dir
    if os.environ.get("STO_EXPECT_SANITIZED") != "1":
        return
    assert observer_fmu.parent == fmu_dir(), "tests/conftest.py's fixtures are not redirected"
    Raw(OBS).free()
    maps = open("/proc/self/maps").read()
    assert "libasan" in maps, "libasan is not loaded"
    loaded = [line.split()[-1] for line in maps.splitlines() if line.endswith(f"{OBS}.so")]
    assert loaded and all("__asan_report_load8" in open(p, "rb").read().decode("latin-1")
                          for p in set(loaded)), loaded
