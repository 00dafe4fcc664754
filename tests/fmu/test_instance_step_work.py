"""The work of one fmi2DoStep is bounded.

FMI 2 gives an importer no way to cancel a synchronous fmi2DoStep, so a
step that needs more internal steps than the parameter max_internal_steps
(default 10^7, value reference 120 in every FMU) is refused with fmi2Error
and a message naming the limit and the parameter, before any work: the
call returns at once and the instance's outputs are untouched.  Raising the
parameter allows longer steps.  Each case runs in a forked child with a
timeout: a step that does the work anyway fails by the timeout.
"""
from __future__ import annotations

import math
import time

import pytest

from tools.abuse.abuse_fmi import ERROR, MODELS, OK, Raw, assert_usable_after_reset, isolated

OBS, PEN, CTL, ROBOT, *_ = MODELS
DEFAULT_LIMIT = 10_000_000
LIMIT_VR = 120
INT_MAX = 2**31 - 1
# a refused step returns at once; a step that ran its steps would take hours
QUICK = 0.5  # s
TIMEOUT = 20.0  # s, per case

DEFAULT_H = {OBS: 1e-4, PEN: 1e-5, CTL: 1e-4, ROBOT: 1e-3, "ModelObserver": 1e-3}
OUTPUTS = {OBS: ["x1_hat[1]", "x2_hat[1]", "theta_hat[1,1]", "gamma_trace"],
           PEN: ["theta", "omega", "acceleration"], CTL: ["u", "theta_d", "omega_d"],
           ROBOT: ["q_hat[1]", "qd_hat[2]", "base_estimate[1]", "gamma_trace"],
           "ModelObserver": ["position_estimate_1", "velocity_1", "theta_1", "theta_std_1"]}


def _limit_message(f: Raw, needed: int, limit: int):
    errors = f.errors()
    assert f"needs {needed} internal steps of h = " in errors, errors
    assert f"more than the limit max_internal_steps = {limit}" in errors, errors
    assert "raise the parameter max_internal_steps (value reference 120)" in errors, errors


def _refused_quickly(f: Raw, t: float, H: float) -> None:
    before = f.get_real(OUTPUTS[f.model])[1]
    start = time.perf_counter()
    status = f.do_step(t, H)
    took = time.perf_counter() - start
    assert status == ERROR, (status, f.messages())
    assert took < QUICK, f"the refused step took {took:.2f} s: work was done"
    after = f.get_real(OUTPUTS[f.model])[1]  # getters stay allowed in the Error state
    assert after == before or all(math.isnan(a) and math.isnan(b) for a, b in zip(after, before))


def _huge_step(model: str, parameters: dict, t0: float, H: float, steps_before: int):
    """A step of H (after some good steps) is refused at once, naming the limit."""
    f = Raw(model)
    assert f.initialize(parameters, start=t0) <= 1, f.messages()
    h = f.get_real(["h"])[1][0]
    step = 10 * h
    t = t0
    for _ in range(steps_before):
        assert f.do_step(t, step) == OK, f.messages()
        t += step
    saved = f.get_state()
    f.clear_log()
    _refused_quickly(f, t, H)
    assert "max_internal_steps" in f.errors()
    f.assert_escaped()
    # the instance is intact: back to the saved state, one normal step on
    assert f.call("fmi2SetFMUstate", saved) == OK
    assert f.do_step(t, step) == OK, f.messages()
    assert_usable_after_reset(f)
    f.free()


HUGE = []
for m in MODELS:
    for H in (1e9, 1e6, 2.0 * DEFAULT_LIMIT * DEFAULT_H[m], 1e15):
        for before in (0, 3):
            HUGE.append((m, {}, 0.0, H, before))
    HUGE.append((m, {"h": 1e-12}, 0.0, 1e-3, 0))   # a tiny h: 10^9 steps in one ms
    HUGE.append((m, {}, 1e6, 1e9 * DEFAULT_H[m], 2))  # far from t = 0: 10^9 steps
HUGE.append((OBS, {"identifier": 1, "identifier_start": 0}, 0.0, 1e6, 1))  # LSM: 6 min before
HUGE.append((OBS, {"identifier": 2, "scheme": 1}, 0.0, 1e5, 1))
HUGE.append((PEN, {"damping": 1, "disturbance": 1}, 0.0, 1e9, 1))


@pytest.mark.parametrize("model, parameters, t0, H, before", HUGE,
                         ids=[f"{c[0]}-{c[1]}-t0={c[2]:g}-H={c[3]:g}-after-{c[4]}" for c in HUGE])
def test_a_step_over_the_limit_is_refused_before_any_work(model, parameters, t0, H, before):
    isolated(_huge_step, model, parameters, t0, H, before, timeout=TIMEOUT)


def _at_the_limit(model: str, limit: int, multiple: float, expect: int):
    """A step of `multiple` internal steps with max_internal_steps = limit."""
    f = Raw(model)
    assert f.initialize({"max_internal_steps": limit}) == OK, f.messages()
    h = f.get_real(["h"])[1][0]
    assert f.do_step(0.0, h) == OK  # one step first: the count is per call, not since start
    status = f.do_step(h, multiple * h)
    assert status == expect, (status, f.messages())
    if expect == ERROR:
        _limit_message(f, math.floor(multiple + 1 + 1e-3) - 1, limit)
    f.assert_escaped()
    f.free()


EDGES = []
for m in MODELS:
    for limit in (1, 7, 1000):
        EDGES += [(m, limit, limit, OK), (m, limit, limit + 0.5, OK), (m, limit, limit + 1, ERROR),
                  (m, limit, 2 * limit + 3, ERROR), (m, limit, 0.25, OK)]


@pytest.mark.parametrize("model, limit, multiple, expect", EDGES,
                         ids=[f"{c[0]}-limit={c[1]}-H={c[2]}h" for c in EDGES])
def test_the_limit_is_exact_and_counts_one_call(model, limit, multiple, expect):
    isolated(_at_the_limit, model, limit, multiple, expect, timeout=TIMEOUT)


def _raised_limit(model: str):
    """Raising max_internal_steps allows a step the default refuses."""
    f = Raw(model)
    assert f.initialize({"h": 1e-6}) == OK
    assert f.do_step(0.0, 11.0) == ERROR  # 1.1e7 steps
    _limit_message(f, 11_000_000, DEFAULT_LIMIT)
    f.free()
    f = Raw(model)
    assert f.initialize({"h": 0.01, "max_internal_steps": 12}) == OK
    assert f.do_step(0.0, 0.13) == ERROR
    f.free()
    f = Raw(model)
    assert f.initialize({"h": 0.01, "max_internal_steps": INT_MAX}) == OK
    assert f.do_step(0.0, 1000.0) == OK, f.messages()  # 10^5 steps
    f.free()


@pytest.mark.parametrize("model", MODELS)
def test_raising_the_parameter_allows_longer_steps(model):
    isolated(_raised_limit, model, timeout=TIMEOUT)


def _bad_limit(model: str, value):
    f = Raw(model)
    status = f.set_integer({"max_internal_steps": value})
    assert status == ERROR, f.messages()
    assert f"max_internal_steps = {value} is out of range [1, 2147483647]" in f.errors()
    assert_usable_after_reset(f)
    f.free()


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("value", [0, -1, -2**31])
def test_the_limit_parameter_has_a_range(model, value):
    isolated(_bad_limit, model, value)


def test_the_parameter_is_declared_alike_in_every_fmu():
    for model in MODELS:
        f = Raw(model, instantiate=False)
        variable = f.variables["max_internal_steps"]
        assert (variable.valueReference, variable.type, variable.causality,
                variable.variability) == (LIMIT_VR, "Integer", "parameter", "fixed")
        assert (variable.start, variable.min, variable.max) in (
            ("10000000", "1", "2147483647"), (DEFAULT_LIMIT, 1, INT_MAX))
        assert "refused" in variable.description and "Raise it" in variable.description
