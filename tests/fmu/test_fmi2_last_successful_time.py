"""fmi2LastSuccessfulTime after a failed fmi2DoStep.

Whatever makes a step fail -- the model diverging inside it, a step the FMU
refuses up front (bad size, wrong time, past stopTime, over the work limit)
-- fmi2GetRealStatus(fmi2LastSuccessfulTime) must report the end of the last
successful step (the start time if there was none), on every FMU, for step
sizes on and off the internal grid, from any start time.
"""
from __future__ import annotations

import ctypes

import pytest

from tools.abuse.abuse_fmi import ERROR, MODELS, OK, Raw, isolated

OBS, PEN, CTL, ROBOT, *_ = MODELS
LAST_SUCCESSFUL_TIME = 2  # fmi2StatusKind fmi2LastSuccessfulTime

# Per model: parameters, and inputs set before the failing step, that make the model fail
# in the step (the outputs or state overflow).
DIVERGING = {
    OBS: ({"b": 1e300}, {"u": 1e300}),
    PEN: ({}, {"u": 1e308}),
    CTL: None,  # its outputs are bounded by its parameters: it fails by itself, see below
    ROBOT: ({}, {"u[1]": 1e306, "u[2]": -1e306}),
    "ModelObserver": ({}, {"input_1": 1e308}),
}


def last_successful_time(f: Raw) -> float:
    value = ctypes.c_double(-12345.0)
    assert f.call("fmi2GetRealStatus", LAST_SUCCESSFUL_TIME, ctypes.byref(value)) == OK, \
        f.messages()
    return value.value


def _failure(model: str, kind: str, t0: float, H: float, good: int):
    f = Raw(model)
    parameters = DIVERGING[model][0] if kind == "diverges" and DIVERGING[model] else {}
    stop = t0 + (good + 0.5) * H if kind == "past-stop-time" else None
    assert f.initialize(parameters, start=t0, stop=stop) == OK, f.messages()
    t = t0
    for _ in range(good):
        assert f.do_step(t, H) == OK, f.messages()
        t += H
    assert last_successful_time(f) == t
    if kind == "diverges":  # within the next steps (a step short of h may reach no grid point)
        assert f.set(DIVERGING[model][1]) == OK
        for _ in range(100):
            status = f.do_step(t, H)
            if status != OK:
                break
            t += H
    elif kind == "bad-size":
        status = f.do_step(t, -H)
    elif kind == "wrong-time":
        status = f.do_step(t + 3 * H, H)
    elif kind == "past-stop-time":
        status = f.do_step(t, 2 * H)
    elif kind == "over-the-limit":
        status = f.do_step(t, 1e9)
    else:
        raise AssertionError(kind)
    assert status == ERROR, (status, f.messages())
    assert last_successful_time(f) == t, (last_successful_time(f), t, f.messages())
    # and again after a second failed call in the Error state
    assert f.do_step(t, H) == ERROR
    assert last_successful_time(f) == t
    f.free()


KINDS = ("diverges", "bad-size", "wrong-time", "past-stop-time", "over-the-limit")
CASES = []
for m in MODELS:
    for kind in KINDS:
        if kind == "diverges" and DIVERGING[m] is None:
            continue
        for t0, H, good in ((0.0, 1e-3, 1), (0.0, 1e-3, 0), (5.0, 2.5e-4, 3), (0.0, 3.7e-3, 2),
                            (-1.0, 1e-5, 4)):
            CASES.append((m, kind, t0, H, good))


@pytest.mark.parametrize("model, kind, t0, H, good", CASES,
                         ids=[f"{c[0]}-{c[1]}-t0={c[2]:g}-H={c[3]:g}-good={c[4]}" for c in CASES])
def test_last_successful_time_is_the_end_of_the_last_good_step(model, kind, t0, H, good):
    isolated(_failure, model, kind, t0, H, good)


def _controller_overflows():
    """The controller's reference overflows by itself after a while (A1, A2 near the
    top of the double range): the step that overflows fails, the one before counts."""
    f = Raw(CTL)
    assert f.initialize({"A1": 5e307, "A2": 5e307, "w1": 3.5}) == OK, f.messages()
    H, t = 1e-3, 0.0
    for _ in range(5000):
        if f.do_step(t, H) != OK:
            break
        t += H
    else:
        raise AssertionError("the controller never failed")
    assert "is not finite" in f.errors()
    assert t > 0.0
    assert last_successful_time(f) == t


def test_last_successful_time_of_a_controller_that_overflows():
    isolated(_controller_overflows)
